#include "gipsi/base/json_node.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/file_io.h"

namespace gipsi {
namespace {

/// Largest JSON file JsonDocument::ParseFile reads [bytes].
constexpr std::uintmax_t kMaxJsonFileBytes = 16u << 20;

std::string Describe(const nlohmann::ordered_json& j) {
  std::string s = j.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

std::string JoinQuoted(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) {
    if (!out.empty()) out += ", ";
    out += "'" + n + "'";
  }
  return out;
}

}  // namespace

JsonNode::JsonNode(const nlohmann::ordered_json& value, std::string file, std::string path)
    : value_(&value),
      file_(std::make_shared<const std::string>(std::move(file))),
      path_(std::move(path)) {}

void JsonNode::Fail(std::string_view what) const {
  // A message that already names this file (an error from deeper in the same document, passed
  // up through a caller that adds its own path) is complete: prefixing it again would print
  // "scene.json: objects.cube: scene.json: objects.cube.domain: ...".
  if (!file_->empty() && what.starts_with(*file_ + ": ")) throw InputError(std::string(what));
  ThrowInputError(*file_, path_.empty() ? "(document root)" : path_, what);
}

void JsonNode::Expected(std::string_view what) const {
  // `what` may already say what it got ("a positive quantity, got -1 s"): do not repeat it.
  if (what.find(", got ") != std::string_view::npos) Fail(fmt::format("expected {}", what));
  Fail(fmt::format("expected {}, got {}", what, Describe(*value_)));
}

bool JsonNode::Has(std::string_view key) const {
  if (!value_->is_object()) Expected("an object");
  return value_->contains(key);
}

JsonNode JsonNode::At(std::string_view key) const {
  auto found = Find(key);
  if (!found) Fail(fmt::format("missing required key '{}'", key));
  return *found;
}

std::optional<JsonNode> JsonNode::Find(std::string_view key) const {
  if (!value_->is_object()) Expected("an object");
  auto it = value_->find(key);
  if (it == value_->end()) return std::nullopt;
  std::string child = path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  return JsonNode(*it, file_, std::move(child));
}

JsonNode JsonNode::Item(std::size_t i) const {
  if (!value_->is_array()) Expected("an array");
  if (i >= value_->size()) Fail(fmt::format("index {} out of range (size {})", i, size()));
  return JsonNode((*value_)[i], file_, fmt::format("{}[{}]", path_, i));
}

std::vector<JsonNode> JsonNode::Items() const {
  if (!value_->is_array()) Expected("an array");
  std::vector<JsonNode> out;
  out.reserve(value_->size());
  for (std::size_t i = 0; i < value_->size(); ++i) out.push_back(Item(i));
  return out;
}

std::vector<std::pair<std::string, JsonNode>> JsonNode::Members() const {
  if (!value_->is_object()) Expected("an object");
  std::vector<std::pair<std::string, JsonNode>> out;
  for (auto it = value_->begin(); it != value_->end(); ++it) {
    std::string child = path_.empty() ? it.key() : path_ + "." + it.key();
    out.emplace_back(it.key(), JsonNode(it.value(), file_, std::move(child)));
  }
  return out;
}

void JsonNode::CheckKeys(std::initializer_list<std::string_view> allowed) const {
  std::vector<std::string> v(allowed.begin(), allowed.end());
  CheckKeys(v);
}

void JsonNode::CheckKeys(const std::vector<std::string>& allowed) const {
  if (!value_->is_object()) Expected("an object");
  for (auto it = value_->begin(); it != value_->end(); ++it) {
    if (std::find(allowed.begin(), allowed.end(), it.key()) == allowed.end()) {
      Fail(fmt::format("unknown key '{}'{}; allowed keys: {}", it.key(),
                       SuggestClosest(it.key(), allowed), JoinQuoted(allowed)));
    }
  }
}

double JsonNode::AsNumber() const {
  if (!value_->is_number()) Expected("a number");
  double v = value_->get<double>();
  if (!std::isfinite(v)) Expected("a finite number");
  return v;
}

double JsonNode::AsPositive() const {
  if (!value_->is_number()) Expected("a positive number");
  double v = value_->get<double>();
  if (!std::isfinite(v) || v <= 0.0) Expected("a positive number");
  return v;
}

double JsonNode::AsNonNegative() const {
  if (!value_->is_number()) Expected("a non-negative number");
  double v = value_->get<double>();
  if (!std::isfinite(v) || v < 0.0) Expected("a non-negative number");
  return v;
}

std::int64_t JsonNode::AsInt() const {
  if (value_->is_number_integer()) return value_->get<std::int64_t>();
  if (value_->is_number_float()) {
    double v = value_->get<double>();
    if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 9e15)
      return static_cast<std::int64_t>(v);
  }
  Expected("an integer");
}

bool JsonNode::AsBool() const {
  if (!value_->is_boolean()) Expected("true or false");
  return value_->get<bool>();
}

std::string JsonNode::AsString() const {
  if (!value_->is_string()) Expected("a string");
  return value_->get<std::string>();
}

Vec3 JsonNode::AsVec3() const {
  if (!value_->is_array() || value_->size() != 3) Expected("an array of 3 numbers");
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = Item(static_cast<std::size_t>(i)).AsNumber();
  return v;
}

std::vector<double> JsonNode::AsNumbers() const {
  if (!value_->is_array()) Expected("an array of numbers");
  std::vector<double> out;
  for (const auto& item : Items()) out.push_back(item.AsNumber());
  return out;
}

std::vector<std::int64_t> JsonNode::AsInts() const {
  if (!value_->is_array()) Expected("an array of integers");
  std::vector<std::int64_t> out;
  for (const auto& item : Items()) out.push_back(item.AsInt());
  return out;
}

std::vector<std::string> JsonNode::AsStrings() const {
  if (!value_->is_array()) Expected("an array of strings");
  std::vector<std::string> out;
  for (const auto& item : Items()) out.push_back(item.AsString());
  return out;
}

std::string JsonNode::AsChoice(std::initializer_list<std::string_view> choices) const {
  std::vector<std::string> names(choices.begin(), choices.end());
  if (!value_->is_string()) Expected(fmt::format("one of {}", JoinQuoted(names)));
  std::string s = value_->get<std::string>();
  if (std::find(names.begin(), names.end(), s) == names.end())
    Expected(fmt::format("one of {}", JoinQuoted(names)));
  return s;
}

double JsonNode::Number(std::string_view key, double fallback) const {
  auto n = Find(key);
  return n ? n->AsNumber() : fallback;
}
double JsonNode::Positive(std::string_view key, double fallback) const {
  auto n = Find(key);
  return n ? n->AsPositive() : fallback;
}
double JsonNode::NonNegative(std::string_view key, double fallback) const {
  auto n = Find(key);
  return n ? n->AsNonNegative() : fallback;
}
std::int64_t JsonNode::Int(std::string_view key, std::int64_t fallback) const {
  auto n = Find(key);
  return n ? n->AsInt() : fallback;
}
bool JsonNode::Bool(std::string_view key, bool fallback) const {
  auto n = Find(key);
  return n ? n->AsBool() : fallback;
}
std::string JsonNode::String(std::string_view key, std::string_view fallback) const {
  auto n = Find(key);
  return n ? n->AsString() : std::string(fallback);
}
Vec3 JsonNode::Vector3(std::string_view key, const Vec3& fallback) const {
  auto n = Find(key);
  return n ? n->AsVec3() : fallback;
}

namespace {

/// Finds duplicate keys while nlohmann parses (it would keep one of them silently): a parser
/// callback that tracks the path of the value being parsed and the keys of each open object.
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(std::string name) : name_(std::move(name)) {}
  bool operator()(int /*depth*/, nlohmann::ordered_json::parse_event_t event,
                  nlohmann::ordered_json& parsed) {
    using Event = nlohmann::ordered_json::parse_event_t;
    switch (event) {
      case Event::object_start:
      case Event::array_start:
        EnterValue();
        frames_.push_back({event == Event::array_start, {}, {}, -1});
        break;
      case Event::object_end:
      case Event::array_end:
        frames_.pop_back();
        break;
      case Event::key: {
        Frame& frame = frames_.back();
        std::string key = parsed.get<std::string>();
        if (std::find(frame.keys.begin(), frame.keys.end(), key) != frame.keys.end())
          ThrowInputError(name_, frames_.size() == 1 ? "(document root)" : Path(frames_.size()),
                          fmt::format("duplicate key '{}' (JSON keys must be unique: one of "
                                      "the two would be ignored)",
                                      key));
        frame.keys.push_back(key);
        frame.key = std::move(key);
        break;
      }
      case Event::value:
        EnterValue();
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool array;
    std::vector<std::string> keys;  // of an object, so far
    std::string key;                // of an object: the current member
    std::int64_t index;             // of an array: the current item
  };
  void EnterValue() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
  }
  /// The JSON path of the first `depth` frames, as JsonNode writes it ("objects.cube.fix[0]").
  [[nodiscard]] std::string Path(std::size_t depth) const {
    std::string path;
    for (std::size_t i = 0; i + 1 < depth; ++i) {
      const Frame& f = frames_[i];
      if (f.array)
        path += fmt::format("[{}]", f.index);
      else
        path += (path.empty() ? "" : ".") + f.key;
    }
    return path;
  }

  std::string name_;
  std::vector<Frame> frames_;
};

}  // namespace

JsonDocument JsonDocument::Parse(std::string_view text, std::string name) {
  auto json = std::make_unique<nlohmann::ordered_json>();
  try {
    *json = nlohmann::ordered_json::parse(text.begin(), text.end(), DuplicateKeyCheck(name));
  } catch (const nlohmann::ordered_json::parse_error& e) {
    // Translate the byte offset into line and column.
    std::size_t byte = std::min<std::size_t>(e.byte == 0 ? 0 : e.byte - 1, text.size());
    std::size_t line = 1, col = 1;
    for (std::size_t i = 0; i < byte; ++i) {
      if (text[i] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    // nlohmann's message is "[json.exception.parse_error.101] parse error at line L, column C:
    // X"; X may hold ": " itself ("last read: '{"a": N'"), so cut after the position's colon.
    std::string what = e.what();
    std::string detail = what;
    if (const auto at = what.find("parse error"); at != std::string::npos)
      if (const auto colon = what.find(": ", at); colon != std::string::npos)
        detail = what.substr(colon + 2);
    // "syntax error while parsing value - invalid literal; last read: '... N'": JSON has no NaN
    // or infinity literals.
    if ((detail.find("invalid literal") != std::string::npos ||
         detail.find("invalid number") != std::string::npos) &&
        byte < text.size()) {
      const std::size_t start = text.find_last_of(" \t\r\n:,[", byte) + 1;
      const char first = start < text.size() ? text[start] : ' ';
      const char second = start + 1 < text.size() ? text[start + 1] : ' ';
      if (std::string_view("NnIi").find(first) != std::string_view::npos ||
          (first == '-' && std::string_view("NnIi").find(second) != std::string_view::npos))
        detail += " (JSON has no NaN or infinity literals: give a finite number)";
    }
    ThrowInputError(name, fmt::format("line {}, column {}", line, col),
                    fmt::format("invalid JSON: {}", detail));
  } catch (const nlohmann::ordered_json::exception& e) {
    // e.g. out_of_range 406 for a number literal that overflows a double (1e999).
    std::string what = e.what();
    auto pos = what.find("] ");
    ThrowInputError(
        name, "",
        fmt::format("invalid JSON: {}", pos == std::string::npos ? what : what.substr(pos + 2)));
  }
  return JsonDocument(std::move(json), std::move(name));
}

JsonDocument JsonDocument::ParseFile(const std::filesystem::path& file) {
  return Parse(ReadRegularFile(file, kMaxJsonFileBytes, "JSON file"), file.string());
}

std::size_t EditDistance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      std::size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string SuggestClosest(std::string_view name, const std::vector<std::string>& candidates) {
  std::size_t best = std::string::npos;
  const std::string* best_name = nullptr;
  for (const auto& c : candidates) {
    std::size_t d = EditDistance(name, c);
    if (d < best) {
      best = d;
      best_name = &c;
    }
  }
  if (best_name && best <= std::max<std::size_t>(2, name.size() / 3))
    return fmt::format(" (did you mean '{}'?)", *best_name);
  return "";
}

}  // namespace gipsi
