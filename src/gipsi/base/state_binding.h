#pragma once
/// @file
/// `StateBinding`: a state value type (state_value.h) held by its owner (an object's, a
/// connector's or an aggregate monitor's `state_` member) and reached through a type-free
/// interface, so that the owner's base class can take snapshots of it (object_state.h) and write
/// and read it in checkpoints (state.h) without knowing its type. `BindStateValue(state)` makes
/// one; SimObject::BindState, Connector::BindState and AggregateObject::BindAggregateState keep
/// it. A state that lives in several parts of its owner (a haptic probe's device, tick and
/// safety stage) is bound as a *gathered* value instead, `BindGatheredStateValue<S>(get, set)`:
/// `get(S&)` copies the parts into a value, `set(const S&)` copies a value back (validating it
/// first, throwing InputError before changing anything). Snapshots then hold an `S` and
/// checkpoints write one; only the copying in and out is the owner's code.
///
/// If `S` declares `static constexpr std::string_view kTag` and `std::uint32_t kVersion`,
/// checkpoints wrap its fields in a section of that tag and version, so a checkpoint written
/// before its fields changed is refused by name (raise the version when they change).

#include <concepts>
#include <cstdint>
#include <functional>
#include <memory>
#include <string_view>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/base/export.h"
#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/base/state_value.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A bound state value, behind a type-free interface. Not copyable.
class StateBinding {
 public:
  StateBinding() = default;
  StateBinding(const StateBinding&) = delete;
  StateBinding& operator=(const StateBinding&) = delete;
  virtual ~StateBinding() = default;

  /// A snapshot box holding a copy of the current state (a StateBox<S>).
  [[nodiscard]] virtual std::unique_ptr<ObjectState> New() const = 0;
  /// Copies the current state into `into` (a box from New); allocation-free for equal shapes.
  virtual void Copy(ObjectState& into) const = 0;
  /// Replaces the current state by the one in `from` (a box from New), in its storage.
  virtual void Set(const ObjectState& from) = 0;
  /// Checkpoints: writes the fields (in the type's section if it declares one).
  virtual void Write(StateWriter& out) const = 0;
  /// Reads the fields into a copy of the current state (so fields sized by the scene are
  /// checked against it), then calls `before_replace(in)` (e.g. the owner's solver caches,
  /// written after the state), and only then replaces the state: a read that throws leaves it
  /// as it was.
  virtual void Read(StateReader& in,
                    const std::function<void(StateReader&)>& before_replace = {}) = 0;
};

namespace state_detail {

template <class S>
concept VersionedState = requires {
  { S::kTag } -> std::convertible_to<std::string_view>;
  { S::kVersion } -> std::convertible_to<std::uint32_t>;
};

template <class S>
class BoundStateValue final : public StateBinding {
 public:
  explicit BoundStateValue(S& state) : state_(state) {}
  [[nodiscard]] std::unique_ptr<ObjectState> New() const override {
    return std::make_unique<StateBox<S>>(state_);
  }
  void Copy(ObjectState& into) const override { CopyFields(StateBox<S>::Of(into).value, state_); }
  void Set(const ObjectState& from) override { CopyFields(state_, StateBox<S>::Of(from).value); }
  void Write(StateWriter& out) const override {
    if constexpr (VersionedState<S>) out.BeginSection(S::kTag, S::kVersion);
    WriteFields(out, state_);
    if constexpr (VersionedState<S>) out.EndSection();
  }
  void Read(StateReader& in, const std::function<void(StateReader&)>& before_replace) override {
    S read = state_;  // kFixed fields are checked against the current shapes
    if constexpr (VersionedState<S>) in.BeginSection(S::kTag, S::kVersion);
    ReadFields(in, read);
    if constexpr (VersionedState<S>) in.EndSection();
    if (before_replace) before_replace(in);
    CopyFields(state_, read);  // into the existing storage (kept capacities, references)
  }

 private:
  S& state_;
};

template <class S, class GetFn, class SetFn>
class GatheredStateValue final : public StateBinding {
 public:
  GatheredStateValue(GetFn get, SetFn set) : get_(std::move(get)), set_(std::move(set)) {}
  [[nodiscard]] std::unique_ptr<ObjectState> New() const override {
    auto box = std::make_unique<StateBox<S>>(S{});
    get_(box->value);
    return box;
  }
  void Copy(ObjectState& into) const override { get_(StateBox<S>::Of(into).value); }
  void Set(const ObjectState& from) override { set_(StateBox<S>::Of(from).value); }
  void Write(StateWriter& out) const override {
    S state;
    get_(state);
    if constexpr (VersionedState<S>) out.BeginSection(S::kTag, S::kVersion);
    WriteFields(out, state);
    if constexpr (VersionedState<S>) out.EndSection();
  }
  void Read(StateReader& in, const std::function<void(StateReader&)>& before_replace) override {
    S read;
    get_(read);  // kFixed fields are checked against the current shapes
    if constexpr (VersionedState<S>) in.BeginSection(S::kTag, S::kVersion);
    ReadFields(in, read);
    if constexpr (VersionedState<S>) in.EndSection();
    if (before_replace) before_replace(in);
    try {
      set_(read);
    } catch (const InputError& e) {  // a value no live state can hold: the checkpoint's fault
      in.Fail(e.what());
    }
  }

 private:
  GetFn get_;
  SetFn set_;
};

}  // namespace state_detail

/// Binds `state`, which must outlive the binding (a member of its owner).
template <class S>
[[nodiscard]] std::unique_ptr<StateBinding> BindStateValue(S& state) {
  return std::make_unique<state_detail::BoundStateValue<S>>(state);
}

/// Binds a state kept in parts of its owner: `get(S&)` fills a value from them, `set(const S&)`
/// puts one back (or throws InputError, changing nothing, for a value it cannot take).
template <class S, class GetFn, class SetFn>
[[nodiscard]] std::unique_ptr<StateBinding> BindGatheredStateValue(GetFn get, SetFn set) {
  return std::make_unique<state_detail::GatheredStateValue<S, GetFn, SetFn>>(std::move(get),
                                                                             std::move(set));
}

/// The state of a type that keeps nothing from one step to the next (a connector that only
/// moves values): binding it makes snapshots free and checkpoints empty.
struct NoState {
  template <class Self, class Visitor>
  static void Fields(Self& /*s*/, Visitor& /*v*/) {}
};

}  // namespace gipsi
GIPSI_EXPORT_END
