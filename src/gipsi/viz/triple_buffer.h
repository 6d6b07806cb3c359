#pragma once
/// @file
/// `TripleBuffer<T>`: lock-free hand-over of the latest value from one writer thread (the
/// simulation) to one reader thread (the renderer). The writer fills `back()` and `Publish()`es
/// it; the reader `Acquire()`s the newest published value and reads `front()` for as long as it
/// likes. Neither side ever waits for the other, and neither sees a half-written value.

#include <array>
#include <atomic>
#include <cstdint>

namespace gipsi::viz {

/// Three slots: one the writer owns (back), one the reader owns (front), one in between
/// (middle). Publish swaps back and middle and marks middle fresh; Acquire swaps front and
/// middle if middle is fresh. The slot indices live in one atomic byte, so both swaps are single
/// atomic exchanges. Exactly one writer thread and one reader thread. Not copyable or movable.
template <class T>
class TripleBuffer {
 public:
  TripleBuffer() = default;
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  /// The slot the writer fills (writer thread only). Slots are reused: it holds an older value.
  T& back() { return slots_[back_]; }
  /// Makes back() the newest published value and hands the writer another slot.
  void Publish() {
    const std::uint8_t old =
        middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    back_ = old & kIndexMask;
  }

  /// Takes the newest published value if there is one since the last Acquire; returns whether
  /// front() changed (reader thread only).
  bool Acquire() {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    const std::uint8_t old = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = old & kIndexMask;
    return true;
  }
  /// The value the reader holds (reader thread only); a default T before the first Acquire.
  const T& front() const { return slots_[front_]; }
  /// Every slot, for sizing them all before the threads start (no thread may be running).
  std::array<T, 3>& slots() { return slots_; }

 private:
  static constexpr std::uint8_t kFresh = 0x4;
  static constexpr std::uint8_t kIndexMask = 0x3;
  std::array<T, 3> slots_{};
  std::uint8_t back_ = 0;   // writer's
  std::uint8_t front_ = 1;  // reader's
  std::atomic<std::uint8_t> middle_{2};
};

}  // namespace gipsi::viz
