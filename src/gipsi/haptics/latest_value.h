#pragma once
/// @file
/// `LatestValue<T>`: a lock-free, wait-free single-producer/single-consumer triple buffer. The
/// producer (the simulation, publishing a local model at its own rate) fills `back()` and calls
/// `Publish()`; the consumer (the haptic loop) calls `Fetch()` and reads `front()`, always the
/// most recently published complete value, never a half-written one. No locks, no allocation
/// after construction; T is copied only by the producer, into its own slot.

#include <array>
#include <atomic>
#include <cstdint>

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

 private:
  static constexpr std::uint8_t kIndex = 3, kFresh = 4;
  std::array<T, 3> slots_;
  std::uint8_t back_ = 0;                // producer's slot
  std::atomic<std::uint8_t> middle_{1};  // exchanged slot (+ fresh flag)
  std::uint8_t front_ = 2;               // consumer's slot
};

}  // namespace gipsi
