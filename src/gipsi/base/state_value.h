#pragma once
/// @file
/// State value types: what an object carries from one step to the next, as a plain struct that
/// lists its fields once, and the generic operations on it (copy, compare, write, read).
///
/// A state value type is a copyable struct `S` with a static member
///
///     template <class Self, class Visitor>
///     static void Fields(Self& s, Visitor& v) {
///       v("x", s.x, Shape::kFixed);  // sized by the scene: a read must match its shape
///       v("history", s.history);     // may change shape (resized on read)
///     }
///
/// `Self` is `S` or `const S`, so one list serves reading and writing. Field types: arithmetic
/// and enum scalars, `std::string`, dense Eigen matrices (fixed or dynamic size),
/// `std::vector` and `std::array` of arithmetic or enum values, `std::vector` of fixed-size
/// Eigen matrices, nested state value types (and `std::vector`s of them), and `Stamped<T>` of
/// any of these (a rarely written field, copied only when it changed).
///
/// - `CopyFields(to, from)` copies the listed fields (a type may keep derived members outside
///   the list, e.g. per-step coefficients; they are not copied). Eigen and `std::vector` reuse
///   their storage when the shapes agree, so copying into a snapshot of the same object
///   allocates nothing.
/// - `FirstDifference(a, b)` compares bit for bit (NaNs with the same bits are equal, +0 and −0
///   differ) and names the first field that differs, e.g. "scheme.x[12]".
/// - `WriteFields` / `ReadFields` serialise through StateWriter / StateReader (state.h): the
///   byte order is the machine's (checkpoints are native, like the rest of state.h), every
///   entry is typed and every kFixed field's shape or value is checked on reading.

#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/base/state.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// How a field may change between a state and its serialised copy.
enum class Shape : std::uint8_t {
  kAny,    ///< resized (or replaced) on reading
  kFixed,  ///< sized by the scene (arrays) or fixed by it (scalars): a read must match
};

/// A state field that is written rarely (fibres, a field written from outside): copying it
/// copies the value only when the stamps differ, so a snapshot of an object whose fibres never
/// change does not copy them every step. Every change goes through `Write()`, which draws a new
/// stamp; do not keep the reference it returns past the change. Copyable and movable.
template <class T>
class Stamped {
 public:
  Stamped() = default;
  explicit Stamped(T value) : value_(std::move(value)), stamp_(NewStateStamp()) {}
  Stamped(const Stamped&) = default;
  Stamped(Stamped&&) noexcept = default;
  Stamped& operator=(Stamped&&) noexcept = default;
  Stamped& operator=(const Stamped& other) {
    if (stamp_ != other.stamp_) {
      value_ = other.value_;
      stamp_ = other.stamp_;
    }
    return *this;
  }
  ~Stamped() = default;

  [[nodiscard]] const T& get() const { return value_; }
  /// The value, to change it (a new stamp).
  [[nodiscard]] T& Write() {
    stamp_ = NewStateStamp();
    return value_;
  }
  [[nodiscard]] std::uint64_t stamp() const { return stamp_; }

 private:
  T value_{};
  std::uint64_t stamp_ = 0;  // 0: never written (the default value)
};

namespace state_detail {

template <class T>
struct IsStamped : std::false_type {};
template <class T>
struct IsStamped<Stamped<T>> : std::true_type {};

template <class T>
struct IsVector : std::false_type {};
template <class T, class A>
struct IsVector<std::vector<T, A>> : std::true_type {};

template <class T>
struct IsArray : std::false_type {};
template <class T, std::size_t N>
struct IsArray<std::array<T, N>> : std::true_type {};

template <class T>
inline constexpr bool kIsScalar = std::is_arithmetic_v<T> || std::is_enum_v<T>;

template <class T>
inline constexpr bool kIsEigen = std::is_base_of_v<Eigen::DenseBase<T>, T>;

template <class T, bool = kIsEigen<T>>
struct IsFixedEigen : std::false_type {};
template <class T>
struct IsFixedEigen<T, true> : std::bool_constant<T::RowsAtCompileTime != Eigen::Dynamic &&
                                                  T::ColsAtCompileTime != Eigen::Dynamic> {};
template <class T>
inline constexpr bool kIsFixedEigen = IsFixedEigen<T>::value;

/// A dynamic size with inline storage of a maximum size (e.g. Matrix<double, Dynamic, Dynamic,
/// ColMajor, 60, 60>; not VecX, whose one fixed dimension is not a bound on a dynamic one).
template <class T, bool = kIsEigen<T>>
struct IsBoundedEigen : std::false_type {};
template <class T>
struct IsBoundedEigen<T, true>
    : std::bool_constant<
          (T::RowsAtCompileTime == Eigen::Dynamic && T::MaxRowsAtCompileTime != Eigen::Dynamic) ||
          (T::ColsAtCompileTime == Eigen::Dynamic && T::MaxColsAtCompileTime != Eigen::Dynamic)> {};
template <class T>
inline constexpr bool kIsBoundedEigen = IsBoundedEigen<T>::value;

/// Calls `v(name, field, shape)` for every field of `s` (const or not).
template <class S, class V>
void Visit(S& s, V& v) {
  std::remove_const_t<S>::Fields(s, v);
}

// --- writing ---
struct Writer {
  StateWriter& out;
  template <class T>
  void operator()(std::string_view /*name*/, const T& x, Shape /*shape*/ = Shape::kAny) {
    Write(x);
  }
  template <class T>
  void Write(const T& x) {
    if constexpr (IsStamped<T>::value) {
      Write(x.get());
    } else if constexpr (std::is_same_v<T, double> || std::is_same_v<T, float>) {
      out.WriteDouble(static_cast<double>(x));
    } else if constexpr (kIsScalar<T>) {
      out.WriteInt(static_cast<std::int64_t>(x));
    } else if constexpr (std::is_same_v<T, std::string>) {
      out.WriteString(x);
    } else if constexpr (kIsEigen<T>) {
      out.WriteMatrix(x);
    } else if constexpr (IsVector<T>::value || IsArray<T>::value) {
      using E = typename T::value_type;
      if constexpr (kIsScalar<E>) {
        out.WriteArray(std::span<const E>(x.data(), x.size()));
      } else if constexpr (kIsFixedEigen<E>) {
        using Scalar = typename E::Scalar;
        static_assert(sizeof(E) == sizeof(Scalar) * E::SizeAtCompileTime);
        out.WriteArray(std::span<const Scalar>(x.empty() ? nullptr : x.front().data(),
                                               x.size() * E::SizeAtCompileTime));
      } else {
        out.WriteInt(static_cast<std::int64_t>(x.size()));
        for (const E& e : x) Write(e);
      }
    } else {
      static_assert(std::is_class_v<T>, "not a state field type");
      Visit(x, *this);
    }
  }
};

// --- reading ---
struct Reader {
  StateReader& in;
  std::string prefix;
  template <class T>
  void operator()(std::string_view name, T& x, Shape shape = Shape::kAny) {
    Read(x, prefix + std::string(name), shape);
  }
  template <class T>
  void Read(T& x, const std::string& name, Shape shape) {
    if constexpr (IsStamped<T>::value) {
      Read(x.Write(), name, shape);
    } else if constexpr (std::is_same_v<T, double> || std::is_same_v<T, float>) {
      x = static_cast<T>(in.ReadDouble());
    } else if constexpr (kIsScalar<T>) {
      const std::int64_t value = in.ReadInt();
      if (shape == Shape::kFixed && value != static_cast<std::int64_t>(x))
        in.Fail(fmt::format("{} is {} in the checkpoint but {} in this scene", name, value,
                            static_cast<std::int64_t>(x)));
      x = static_cast<T>(value);
    } else if constexpr (std::is_same_v<T, std::string>) {
      std::string value = in.ReadString();
      if (shape == Shape::kFixed && value != x)
        in.Fail(fmt::format("{} is '{}' in the checkpoint but '{}' in this scene", name, value, x));
      x = std::move(value);
    } else if constexpr (kIsBoundedEigen<T>) {
      ReadBounded(x, name, shape);
    } else if constexpr (kIsEigen<T>) {
      if (shape == Shape::kFixed || kIsFixedEigen<T>)
        in.ReadMatrixExact(x, name);
      else
        in.ReadMatrix(x);
    } else if constexpr (IsVector<T>::value || IsArray<T>::value) {
      using E = typename T::value_type;
      if constexpr (kIsScalar<E>) {
        if constexpr (IsVector<T>::value) {
          if (shape == Shape::kAny) return in.ReadArray(x);
          in.ReadArrayExact(x, name);
        } else {
          std::vector<E> values(x.size());
          in.ReadArrayExact(values, name);
          std::copy(values.begin(), values.end(), x.begin());
        }
      } else if constexpr (kIsFixedEigen<E>) {
        using Scalar = typename E::Scalar;
        std::vector<Scalar> values;
        if (shape == Shape::kFixed) {
          values.resize(x.size() * E::SizeAtCompileTime);
          in.ReadArrayExact(values, name);
        } else {
          in.ReadArray(values);
          if (values.size() % E::SizeAtCompileTime != 0)
            in.Fail(fmt::format("{}: {} values are not whole {}-by-{} matrices", name,
                                values.size(), E::RowsAtCompileTime, E::ColsAtCompileTime));
          if constexpr (IsVector<T>::value) x.resize(values.size() / E::SizeAtCompileTime);
        }
        for (std::size_t i = 0; i < x.size(); ++i)
          x[i] = Eigen::Map<const E>(values.data() + i * E::SizeAtCompileTime);
      } else {
        const std::int64_t count = in.ReadInt();
        if (count < 0 || (shape == Shape::kFixed && count != static_cast<std::int64_t>(x.size())))
          in.Fail(fmt::format("{} has {} entries in the checkpoint but {} in this scene", name,
                              count, x.size()));
        if constexpr (IsVector<T>::value) x.resize(static_cast<std::size_t>(count));
        for (std::size_t i = 0; i < x.size(); ++i)
          Read(x[i], fmt::format("{}[{}]", name, i), shape);
      }
    } else {
      static_assert(std::is_class_v<T>, "not a state field type");
      Reader nested{in, name + "."};
      Visit(x, nested);
    }
  }
  /// A matrix of dynamic size with inline storage (a maximum size): a size that does not fit
  /// the storage is refused, not written past it.
  template <class T>
  void ReadBounded(T& x, const std::string& name, Shape shape) {
    Eigen::Matrix<typename T::Scalar, Eigen::Dynamic, Eigen::Dynamic> m;
    in.ReadMatrix(m);
    const bool fits =
        (T::MaxRowsAtCompileTime == Eigen::Dynamic || m.rows() <= T::MaxRowsAtCompileTime) &&
        (T::MaxColsAtCompileTime == Eigen::Dynamic || m.cols() <= T::MaxColsAtCompileTime) &&
        (T::RowsAtCompileTime == Eigen::Dynamic || m.rows() == T::RowsAtCompileTime) &&
        (T::ColsAtCompileTime == Eigen::Dynamic || m.cols() == T::ColsAtCompileTime);
    if (!fits)
      in.Fail(
          fmt::format("{} is {} by {} in the checkpoint, more than its storage holds ({} by {})",
                      name, m.rows(), m.cols(), static_cast<int>(T::MaxRowsAtCompileTime),
                      static_cast<int>(T::MaxColsAtCompileTime)));
    if (shape == Shape::kFixed && (m.rows() != x.rows() || m.cols() != x.cols()))
      in.Fail(fmt::format("{} is {} by {} in the checkpoint but {} by {} in this scene", name,
                          m.rows(), m.cols(), x.rows(), x.cols()));
    x.resize(m.rows(), m.cols());
    if (m.size() > 0) x = m;
  }
};

// --- comparing ---
template <class T>
bool SameBits(const T* a, const T* b, std::size_t n) {
  return n == 0 || std::memcmp(a, b, n * sizeof(T)) == 0;
}

/// Index of the first element of [a, a + n) whose bits differ from b's.
template <class T>
std::size_t FirstDifferent(const T* a, const T* b, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    if (std::memcmp(a + i, b + i, sizeof(T)) != 0) return i;
  return n;
}

template <class T>
std::string Compare(const T& a, const T& b, const std::string& name);

/// The addresses of a state's fields, in the order of its Fields (at most kMaxFields per
/// level: a fixed buffer, so copying allocates nothing).
struct FieldAddresses {
  static constexpr std::size_t kMaxFields = 64;
  std::array<const void*, kMaxFields> at{};
  std::size_t count = 0;
  template <class T>
  void operator()(std::string_view /*name*/, const T& x, Shape /*shape*/ = Shape::kAny) {
    if (count == kMaxFields) std::abort();  // a state type with more fields than kMaxFields
    at[count++] = &x;
  }
};

/// Compares b's fields against a's addresses; keeps the first difference.
struct Check {
  const FieldAddresses& a;
  const std::string& prefix;
  std::size_t next = 0;
  std::string difference;
  template <class T>
  void operator()(std::string_view name, const T& x, Shape /*shape*/ = Shape::kAny) {
    const T& other = *static_cast<const T*>(a.at[next++]);
    if (difference.empty()) difference = Compare(other, x, prefix + std::string(name));
  }
};

/// Assigns the source's fields (by address) to the destination's.
struct Assign {
  const FieldAddresses& from;
  std::size_t next = 0;
  template <class T>
  void operator()(std::string_view /*name*/, T& x, Shape /*shape*/ = Shape::kAny) {
    x = *static_cast<const T*>(from.at[next++]);
  }
};

/// Visits the fields of `a` and of `b` in step (same type, so the same list).
template <class S>
std::string CompareFields(const S& a, const S& b, const std::string& prefix) {
  FieldAddresses addresses;
  Visit(a, addresses);
  Check check{addresses, prefix, 0, {}};
  Visit(b, check);
  return check.difference;
}

template <class T>
std::string Compare(const T& a, const T& b, const std::string& name) {
  if constexpr (IsStamped<T>::value) {
    return Compare(a.get(), b.get(), name);
  } else if constexpr (kIsScalar<T>) {
    return SameBits(&a, &b, 1) ? std::string() : name;
  } else if constexpr (std::is_same_v<T, std::string>) {
    return a == b ? std::string() : name;
  } else if constexpr (kIsEigen<T>) {
    if (a.rows() != b.rows() || a.cols() != b.cols())
      return fmt::format("{} (shape {}x{} against {}x{})", name, a.rows(), a.cols(), b.rows(),
                         b.cols());
    const auto n = static_cast<std::size_t>(a.size());
    const std::size_t i = FirstDifferent(a.data(), b.data(), n);
    return i == n ? std::string() : fmt::format("{}[{}]", name, i);
  } else if constexpr (IsVector<T>::value || IsArray<T>::value) {
    if (a.size() != b.size())
      return fmt::format("{} (size {} against {})", name, a.size(), b.size());
    using E = typename T::value_type;
    if constexpr (kIsScalar<E>) {
      const std::size_t i = FirstDifferent(a.data(), b.data(), a.size());
      return i == a.size() ? std::string() : fmt::format("{}[{}]", name, i);
    } else {
      for (std::size_t i = 0; i < a.size(); ++i) {
        std::string d = Compare(a[i], b[i], fmt::format("{}[{}]", name, i));
        if (!d.empty()) return d;
      }
      return {};
    }
  } else {
    static_assert(std::is_class_v<T>, "not a state field type");
    return CompareFields(a, b, name + ".");
  }
}

}  // namespace state_detail

/// Appends every field of `s` to `out`, in the order of `S::Fields` (no section: the caller
/// opens one with the type's tag and version).
template <class S>
void WriteFields(StateWriter& out, const S& s) {
  state_detail::Writer writer{out};
  state_detail::Visit(s, writer);
}

/// Reads what WriteFields wrote into `s`, checking every kFixed field against `s`'s current
/// shape or value; throws InputError naming the field otherwise.
template <class S>
void ReadFields(StateReader& in, S& s) {
  state_detail::Reader reader{in, {}};
  state_detail::Visit(s, reader);
}

/// Copies the fields of `from` into `to` (field by field: members a type keeps outside its
/// Fields list, such as per-step coefficients, are not copied). Allocation-free when the shapes
/// agree.
template <class S>
void CopyFields(S& to, const S& from) {
  state_detail::FieldAddresses addresses;
  state_detail::Visit(from, addresses);
  state_detail::Assign assign{addresses};
  state_detail::Visit(to, assign);
}

/// The first field (with index) whose bits differ between `a` and `b`; empty if none does.
template <class S>
[[nodiscard]] std::string FirstDifference(const S& a, const S& b) {
  return state_detail::CompareFields(a, b, {});
}

}  // namespace gipsi
GIPSI_EXPORT_END
