#pragma once
/// @file
/// Typed, path-aware access to JSON documents (scene files, parameters). Every accessor that
/// finds the wrong type or value throws InputError naming the file, the JSON path and what was
/// expected, e.g. `scene.json: objects.sheet.stiffness: expected a positive number, got "abc"`.

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A read-only view of one value inside a JSON document, with its file name and JSON path.
/// Object members keep their order in the file (declaration order matters for schedules).
/// Cheap to copy; it refers to the document, which must outlive it.
class JsonNode {
 public:
  /// `file` is used only in error messages; `path` is this value's JSON path ("" for the root).
  JsonNode(const nlohmann::ordered_json& value, std::string file, std::string path);

  [[nodiscard]] const std::string& file() const { return *file_; }
  /// The JSON path of this value, e.g. `objects.sheet.material` or `probes[2]`.
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] const nlohmann::ordered_json& raw() const { return *value_; }

  [[nodiscard]] bool is_object() const { return value_->is_object(); }
  [[nodiscard]] bool is_array() const { return value_->is_array(); }
  [[nodiscard]] bool is_string() const { return value_->is_string(); }
  [[nodiscard]] bool is_number() const { return value_->is_number(); }
  /// Number of items of an array or members of an object.
  [[nodiscard]] std::size_t size() const { return value_->size(); }

  /// True if this object has member `key`. Throws if this is not an object.
  [[nodiscard]] bool Has(std::string_view key) const;
  /// The member `key`; throws "missing required key" when absent.
  [[nodiscard]] JsonNode At(std::string_view key) const;
  /// The member `key` if present.
  [[nodiscard]] std::optional<JsonNode> Find(std::string_view key) const;
  /// Item `i` of an array; throws if this is not an array or `i` is out of range.
  [[nodiscard]] JsonNode Item(std::size_t i) const;
  /// All items of an array (throws if not an array).
  [[nodiscard]] std::vector<JsonNode> Items() const;
  /// All members of an object in document order (throws if not an object).
  [[nodiscard]] std::vector<std::pair<std::string, JsonNode>> Members() const;

  /// Throws if this object has a member not in `allowed` (catches typos such as "gravty"),
  /// suggesting the closest allowed key.
  void CheckKeys(std::initializer_list<std::string_view> allowed) const;
  void CheckKeys(const std::vector<std::string>& allowed) const;

  // Conversions of this value; each throws on a wrong type.
  [[nodiscard]] double AsNumber() const;       ///< a finite number
  [[nodiscard]] double AsPositive() const;     ///< a finite number > 0
  [[nodiscard]] double AsNonNegative() const;  ///< a finite number >= 0
  [[nodiscard]] std::int64_t AsInt() const;    ///< an integer
  [[nodiscard]] bool AsBool() const;
  [[nodiscard]] std::string AsString() const;
  [[nodiscard]] Vec3 AsVec3() const;  ///< an array of 3 finite numbers
  [[nodiscard]] std::vector<double> AsNumbers() const;
  [[nodiscard]] std::vector<std::int64_t> AsInts() const;
  [[nodiscard]] std::vector<std::string> AsStrings() const;
  /// A string that must be one of `choices`.
  [[nodiscard]] std::string AsChoice(std::initializer_list<std::string_view> choices) const;

  // Member shortcuts: required, and with a default when absent.
  [[nodiscard]] double Number(std::string_view key) const { return At(key).AsNumber(); }
  [[nodiscard]] double Number(std::string_view key, double fallback) const;
  [[nodiscard]] double Positive(std::string_view key) const { return At(key).AsPositive(); }
  [[nodiscard]] double Positive(std::string_view key, double fallback) const;
  [[nodiscard]] double NonNegative(std::string_view key) const { return At(key).AsNonNegative(); }
  [[nodiscard]] double NonNegative(std::string_view key, double fallback) const;
  [[nodiscard]] std::int64_t Int(std::string_view key) const { return At(key).AsInt(); }
  [[nodiscard]] std::int64_t Int(std::string_view key, std::int64_t fallback) const;
  [[nodiscard]] bool Bool(std::string_view key, bool fallback) const;
  [[nodiscard]] std::string String(std::string_view key) const { return At(key).AsString(); }
  [[nodiscard]] std::string String(std::string_view key, std::string_view fallback) const;
  [[nodiscard]] Vec3 Vector3(std::string_view key) const { return At(key).AsVec3(); }
  [[nodiscard]] Vec3 Vector3(std::string_view key, const Vec3& fallback) const;

  /// Throws InputError "FILE: PATH: what".
  [[noreturn]] void Fail(std::string_view what) const;
  /// Throws InputError "FILE: PATH: expected WHAT, got VALUE".
  [[noreturn]] void Expected(std::string_view what) const;

 private:
  const nlohmann::ordered_json* value_;
  std::shared_ptr<const std::string> file_;
  std::string path_;
  JsonNode(const nlohmann::ordered_json& value, std::shared_ptr<const std::string> file,
           std::string path)
      : value_(&value), file_(std::move(file)), path_(std::move(path)) {}
};

/// An owned, parsed JSON document. Not copyable (nodes point into it); movable.
class JsonDocument {
 public:
  /// Parses `text`; `name` is used in messages. Throws InputError with line and column on a
  /// syntax error.
  static JsonDocument Parse(std::string_view text, std::string name);
  /// Reads and parses a file; throws InputError if it cannot be read or parsed.
  static JsonDocument ParseFile(const std::filesystem::path& file);

  JsonDocument(JsonDocument&&) noexcept = default;
  JsonDocument& operator=(JsonDocument&&) noexcept = default;
  JsonDocument(const JsonDocument&) = delete;
  JsonDocument& operator=(const JsonDocument&) = delete;

  [[nodiscard]] JsonNode root() const { return JsonNode(*json_, name_, ""); }
  [[nodiscard]] const std::string& name() const { return name_; }

 private:
  JsonDocument(std::unique_ptr<nlohmann::ordered_json> json, std::string name)
      : json_(std::move(json)), name_(std::move(name)) {}
  std::unique_ptr<nlohmann::ordered_json> json_;
  std::string name_;
};

/// Levenshtein distance, used to suggest the closest name in "unknown X" errors.
std::size_t EditDistance(std::string_view a, std::string_view b);
/// `" (did you mean 'x'?)"` for the closest candidate within a small distance, else "".
std::string SuggestClosest(std::string_view name, const std::vector<std::string>& candidates);

}  // namespace gipsi
GIPSI_EXPORT_END
