#pragma once
/// @file
/// `LatestValue<T>`: a lock-free, wait-free single-producer/single-consumer triple buffer, the
/// one hand-over between GiPSi's threads: the simulation publishes haptic local models to the
/// haptic loop and display frames to the renderer through it. The producer fills `back()` and
/// calls `Publish()`; the consumer calls `Fetch()` and reads `front()`, always the most recently
/// published complete value, never a half-written one. Neither side ever waits for the other.
/// No locks, no allocation after construction; T is copied only by the producer, into its own
/// slot. Slots are reused: back() holds an older value, to be overwritten.

#include <array>
#include <atomic>
#include <cstdint>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable or movable (the two threads hold references).
template <class T>
class LatestValue {
 public:
  /// All three slots start as `initial`.
  explicit LatestValue(const T& initial = T{}) : slots_{initial, initial, initial} {}
  LatestValue(const LatestValue&) = delete;
  LatestValue& operator=(const LatestValue&) = delete;

  // --- producer ---
  /// The slot the producer writes (not visible to the consumer until Publish).
  T& back() { return slots_[back_]; }
  /// Makes back() the latest value; the producer gets a fresh slot to write next.
  void Publish() {
    const std::uint8_t previous =
        middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    back_ = previous & kIndex;
  }

  // --- consumer ---
  /// Takes the latest published value if there is a new one; returns whether it did.
  bool Fetch() {
    if (!(middle_.load(std::memory_order_relaxed) & kFresh)) return false;
    const std::uint8_t previous = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = previous & kIndex;
    return true;
  }
  /// The value the consumer reads (stable until its next Fetch).
  [[nodiscard]] const T& front() const { return slots_[front_]; }

  // --- checkpoints: only while neither side runs ---
  /// Which slot each side holds, and whether the exchanged slot holds an unfetched value.
  /// Plain struct.
  struct Layout {
    int back = 0, middle = 1, front = 2;
    bool fresh = false;
  };
  [[nodiscard]] Layout layout() const {
    const std::uint8_t middle = middle_.load(std::memory_order_relaxed);
    return {back_, middle & kIndex, front_, (middle & kFresh) != 0};
  }
  /// Restores a layout; returns false (changing nothing) unless the three indices are a
  /// permutation of 0, 1, 2.
  bool set_layout(const Layout& layout) {
    for (int i : {layout.back, layout.middle, layout.front})
      if (i < 0 || i > 2) return false;
    if (((1 << layout.back) | (1 << layout.middle) | (1 << layout.front)) != 7) return false;
    back_ = static_cast<std::uint8_t>(layout.back);
    front_ = static_cast<std::uint8_t>(layout.front);
    middle_.store(static_cast<std::uint8_t>(layout.middle | (layout.fresh ? kFresh : 0)),
                  std::memory_order_relaxed);
    return true;
  }
  /// Slot `i` (0, 1 or 2), whichever side holds it.
  [[nodiscard]] T& slot(int i) { return slots_[static_cast<std::size_t>(i)]; }
  [[nodiscard]] const T& slot(int i) const { return slots_[static_cast<std::size_t>(i)]; }

 private:
  static constexpr std::uint8_t kIndex = 3, kFresh = 4;
  std::array<T, 3> slots_;
  std::uint8_t back_ = 0;                // producer's slot
  std::atomic<std::uint8_t> middle_{1};  // exchanged slot (+ fresh flag)
  std::uint8_t front_ = 2;               // consumer's slot
};

}  // namespace gipsi
GIPSI_EXPORT_END
