#pragma once
/// @file
/// Internal helper: base64 encoding and decoding (RFC 4648 alphabet) as used by VTK XML files.
/// Not part of the public API.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::internal {

/// Base64 encoding of `bytes`, padded with '='.
std::string EncodeBase64(std::string_view bytes);

/// Decodes base64 `text`, ignoring whitespace. Padding ('=') may also occur in the middle, at a
/// 4-character boundary, as when VTK encodes a header and its data separately and concatenates
/// them: the decoded pieces are concatenated. Returns nullopt on an invalid character or a
/// dangling single character; `bad_at` then receives its index in `text`.
std::optional<std::string> DecodeBase64(std::string_view text, std::size_t* bad_at = nullptr);

/// DecodeBase64 of a text handed over in pieces (a file streamed through a buffer): the same
/// bytes and the same errors, the index of a bad character counted from the text's start.
class Base64Decoder {
 public:
  /// Decodes the next piece, appending its whole bytes to `out`; false on an invalid character.
  bool Feed(std::string_view text, std::string& out, std::size_t* bad_at = nullptr);
  /// Ends the text, appending the bytes of a last partial group; false for a dangling single
  /// character (`bad_at`: the text's length).
  bool Finish(std::string& out, std::size_t* bad_at = nullptr);

 private:
  void Flush(std::string& out);  // the bytes of a partial group, which padding ends
  std::uint32_t acc_ = 0;
  int have_ = 0;         // characters of the current 4-character group
  std::size_t fed_ = 0;  // characters before the current piece
};

}  // namespace gipsi::internal
GIPSI_EXPORT_END
