#pragma once
/// @file
/// `DisplayPublisher`: the kernel observer that, on the simulation thread after each macro step,
/// fills the display buffers of every object and publishes them through a triple buffer. The
/// renderer reads only published frames, so drawing never touches live simulation state and
/// neither thread waits for the other.

#include "gipsi/base/export.h"
#include "gipsi/base/latest_value.h"
#include "gipsi/core/kernel.h"
#include "gipsi/viz/display_manager.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// Publishes a `SceneDisplay` into `buffer` (which must outlive the kernel this observer is
/// attached to). Not copyable or movable.
class DisplayPublisher final : public Observer {
 public:
  DisplayPublisher(SceneDisplay display, LatestValue<FrameBuffers>& buffer)
      : display_(std::move(display)), buffer_(buffer) {}
  DisplayPublisher(const DisplayPublisher&) = delete;
  DisplayPublisher& operator=(const DisplayPublisher&) = delete;

  void Observe(const Kernel& /*kernel*/, double t) override {
    display_.Fill(t, buffer_.back());
    buffer_.Publish();
  }
  [[nodiscard]] SceneDisplay& display() { return display_; }

 private:
  SceneDisplay display_;
  LatestValue<FrameBuffers>& buffer_;
};

}  // namespace gipsi::viz
GIPSI_EXPORT_END
