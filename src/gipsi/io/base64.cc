#include "gipsi/io/base64.h"

#include <array>
#include <cstdint>

namespace gipsi::internal {
namespace {

constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

constexpr std::array<std::int8_t, 256> MakeDecodeTable() {
  std::array<std::int8_t, 256> table{};
  for (auto& t : table) t = -1;
  for (int i = 0; i < 64; ++i) table[static_cast<unsigned char>(kAlphabet[i])] = std::int8_t(i);
  return table;
}
constexpr auto kDecode = MakeDecodeTable();

}  // namespace

std::string EncodeBase64(std::string_view bytes) {
  // Written into a sized buffer: a VTU frame encodes megabytes, and appending one character
  // at a time (a capacity check each) took 2 % of the heart demo.
  std::string out((bytes.size() + 2) / 3 * 4, '=');
  char* o = out.data();
  const auto* in = reinterpret_cast<const std::uint8_t*>(bytes.data());
  const std::size_t whole = bytes.size() / 3 * 3;
  for (std::size_t i = 0; i < whole; i += 3, o += 4) {
    const std::uint32_t v = std::uint32_t{in[i]} << 16 | std::uint32_t{in[i + 1]} << 8 | in[i + 2];
    o[0] = kAlphabet[v >> 18];
    o[1] = kAlphabet[(v >> 12) & 63];
    o[2] = kAlphabet[(v >> 6) & 63];
    o[3] = kAlphabet[v & 63];
  }
  const std::size_t rest = bytes.size() - whole;
  if (rest > 0) {  // the padding '=' is already in place
    const std::uint32_t v =
        std::uint32_t{in[whole]} << 16 | (rest == 2 ? std::uint32_t{in[whole + 1]} << 8 : 0);
    o[0] = kAlphabet[v >> 18];
    o[1] = kAlphabet[(v >> 12) & 63];
    if (rest == 2) o[2] = kAlphabet[(v >> 6) & 63];
  }
  return out;
}

void Base64Decoder::Flush(std::string& out) {
  if (have_ == 2) out += static_cast<char>(acc_ >> 4);
  if (have_ == 3) {
    out += static_cast<char>(acc_ >> 10);
    out += static_cast<char>((acc_ >> 2) & 0xff);
  }
  acc_ = 0;
  have_ = 0;
}

bool Base64Decoder::Feed(std::string_view text, std::string& out, std::size_t* bad_at) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    auto c = static_cast<unsigned char>(text[i]);
    if (c == ' ' || c == '\n' || c == '\r' || c == '\t') continue;
    if (c == '=') {
      if (have_ == 1) {
        if (bad_at != nullptr) *bad_at = fed_ + i;
        return false;
      }
      Flush(out);
      continue;
    }
    std::int8_t v = kDecode[c];
    if (v < 0) {
      if (bad_at != nullptr) *bad_at = fed_ + i;
      return false;
    }
    acc_ = acc_ << 6 | static_cast<std::uint32_t>(v);
    if (++have_ == 4) {
      out += static_cast<char>(acc_ >> 16);
      out += static_cast<char>((acc_ >> 8) & 0xff);
      out += static_cast<char>(acc_ & 0xff);
      acc_ = 0;
      have_ = 0;
    }
  }
  fed_ += text.size();
  return true;
}

bool Base64Decoder::Finish(std::string& out, std::size_t* bad_at) {
  if (have_ == 1) {
    if (bad_at != nullptr) *bad_at = fed_;
    return false;
  }
  Flush(out);
  return true;
}

std::optional<std::string> DecodeBase64(std::string_view text, std::size_t* bad_at) {
  std::string out;
  out.reserve(text.size() / 4 * 3);
  Base64Decoder decoder;
  if (!decoder.Feed(text, out, bad_at) || !decoder.Finish(out, bad_at)) return std::nullopt;
  return out;
}

}  // namespace gipsi::internal
