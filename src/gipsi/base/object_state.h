#pragma once
/// @file
/// `ObjectState`: a snapshot of one object's (or connector's) evolving state, held by whoever
/// needs it (the kernel's step retry, a test that steps twice from the same state), without
/// knowing the object's type. Two implementations:
/// - `StateBox<S>` holds a state value type `S` (state_value.h): copying and comparing go field
///   by field (CopyFields, FirstDifference), allocation-free for same-shaped states.
/// - `ByteState` holds the serialised state (state.h), for types that have no value type yet
///   (a plugin that only writes checkpoint hooks, and the built-ins listed in
///   docs/architecture.md).
/// - `CompositeState` holds the snapshots of several parts (a coordinator, an aggregate).

#include <algorithm>
#include <memory>
#include <string>
#include <typeinfo>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/base/export.h"
#include "gipsi/base/state_value.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Base of the snapshot boxes. Not copyable (copy through Assign, which keeps the storage).
class ObjectState {
 public:
  ObjectState() = default;
  ObjectState(const ObjectState&) = delete;
  ObjectState& operator=(const ObjectState&) = delete;
  virtual ~ObjectState() = default;

  /// Makes this a copy of `other`, which must be a box of the same type made by the same
  /// object (checked, abort otherwise).
  virtual void Assign(const ObjectState& other) = 0;
  /// The first field whose bits differ from `other`'s ("" if none), for tests and diagnostics.
  [[nodiscard]] virtual std::string FirstDifference(const ObjectState& other) const = 0;
};

/// An ObjectState of type `T` (the CRTP base of every box type): `T::Of(box)` is `box` as a
/// `T`, checked (aborts naming both types if the box holds another).
template <class T>
class TypedState : public ObjectState {
 public:
  static const T& Of(const ObjectState& box) {
    const auto* typed = dynamic_cast<const T*>(&box);
    GIPSI_CHECK(typed != nullptr, "a snapshot of type {} where {} was expected", typeid(box).name(),
                typeid(T).name());
    return *typed;
  }
  static T& Of(ObjectState& box) {
    return const_cast<T&>(Of(static_cast<const ObjectState&>(box)));
  }
};

/// A state value type `S` in a box.
template <class S>
class StateBox final : public TypedState<StateBox<S>> {
  using Base = TypedState<StateBox<S>>;

 public:
  explicit StateBox(const S& initial) : value(initial) {}

  void Assign(const ObjectState& other) override { CopyFields(value, Of(other).value); }
  [[nodiscard]] std::string FirstDifference(const ObjectState& other) const override {
    return gipsi::FirstDifference(value, Of(other).value);
  }

  using Base::Of;

  S value;
};

/// A serialised state (the bytes StateWriter wrote).
class ByteState final : public TypedState<ByteState> {
 public:
  void Assign(const ObjectState& other) override { bytes = Of(other).bytes; }
  [[nodiscard]] std::string FirstDifference(const ObjectState& other) const override {
    const std::string& b = Of(other).bytes;
    if (bytes.size() != b.size())
      return "the serialised state (" + std::to_string(bytes.size()) + " against " +
             std::to_string(b.size()) + " bytes)";
    const auto [mine, theirs] = std::mismatch(bytes.begin(), bytes.end(), b.begin());
    return mine == bytes.end()
               ? std::string()
               : "the serialised state at byte " + std::to_string(mine - bytes.begin());
  }

  std::string bytes;
};

/// Snapshots of several parts side by side (a coordinator's objects and connectors, an
/// aggregate and its own monitor). Assign and compare part by part.
class CompositeState final : public TypedState<CompositeState> {
 public:
  void Assign(const ObjectState& other) override {
    const CompositeState& o = Of(other);
    GIPSI_CHECK(o.parts.size() == parts.size(), "a composite snapshot of another shape");
    for (std::size_t i = 0; i < parts.size(); ++i) parts[i]->Assign(*o.parts[i]);
  }
  [[nodiscard]] std::string FirstDifference(const ObjectState& other) const override {
    const CompositeState& o = Of(other);
    if (o.parts.size() != parts.size()) return "the number of parts";
    for (std::size_t i = 0; i < parts.size(); ++i) {
      std::string d = parts[i]->FirstDifference(*o.parts[i]);
      if (!d.empty()) return "part " + std::to_string(i) + ": " + d;
    }
    return {};
  }

  std::vector<std::unique_ptr<ObjectState>> parts;
};

}  // namespace gipsi
GIPSI_EXPORT_END
