#pragma once
/// @file
/// Strong index types: an ObjectId cannot be passed where a ConnectorId is expected.

#include <compare>
#include <cstdint>
#include <functional>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A typed index. `Tag` is any (incomplete) type that distinguishes one kind of id from another.
/// Trivially copyable; default-constructed ids are invalid (-1).
template <class Tag>
class StrongId {
 public:
  constexpr StrongId() = default;
  constexpr explicit StrongId(std::int64_t value) : value_(value) {}
  /// The raw index, for subscripting containers.
  [[nodiscard]] constexpr std::int64_t value() const { return value_; }
  [[nodiscard]] constexpr bool is_valid() const { return value_ >= 0; }
  constexpr auto operator<=>(const StrongId&) const = default;

 private:
  std::int64_t value_ = -1;
};

}  // namespace gipsi
GIPSI_EXPORT_END

template <class Tag>
struct std::hash<gipsi::StrongId<Tag>> {
  std::size_t operator()(const gipsi::StrongId<Tag>& id) const noexcept {
    return std::hash<std::int64_t>()(id.value());
  }
};
