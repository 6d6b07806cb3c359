#include "gipsi/haptics/local_model_tick.h"

#include <algorithm>

namespace gipsi {

LocalModelTick::LocalModelTick(HapticDevice& device, const DeviceWorkspace& workspace,
                               LatestValue<LocalDynamicModel>& models,
                               LatestValue<HapticFeedback>* feedback, const LocalTickParams& params)
    : device_(device),
      workspace_(workspace),
      models_(models),
      feedback_(feedback),
      params_(params),
      safety_(params.safety) {}

Vec3 LocalModelTick::Run(double t, double dt) noexcept {
  const DevicePose pose = device_.Read(t);
  const Vec3 x = workspace_.ToSimulation(pose.position);
  tool_ = x;
  if (models_.Fetch()) {
    // Hand-over: re-anchor to the new model; the force offset is set after this tick's step.
    AnchorLocalState(models_.front(), state_);
    anchored_ = true;
    blend_pending_ = true;
    have_depth_ = false;
    ++handovers_;
  }
  const LocalDynamicModel& model = models_.front();
  Vec3 force = Vec3::Zero();
  model_force_ = 0;
  proxy_ = x;
  if (anchored_ && model.active) {
    depth_ = (model.point - x).dot(model.normal);
    const double rate = have_depth_ && dt > 0 ? (depth_ - previous_depth_) / dt : 0.0;
    previous_depth_ = depth_;
    have_depth_ = true;
    model_force_ = StepLocalModel(model, params_.coupling, depth_, rate, state_);
    proxy_depth_ = LocalSurfaceDepth(model, state_);
    proxy_ = x + std::max(0.0, depth_ - proxy_depth_) * model.normal;
    force = model_force_ * model.normal;
  }
  if (blend_pending_) {
    offset_ = rendered_ - force;
    blend_left_ = params_.blend_time;
    blend_pending_ = false;
  }
  if (blend_left_ > 0 && params_.blend_time > 0) {
    rendered_ = force + (blend_left_ / params_.blend_time) * offset_;
    blend_left_ -= dt;
  } else {
    rendered_ = force;
  }
  // A contact only pushes: the fading offset may not pull the device into the tissue.
  const double normal_part = rendered_.dot(model.normal);
  if (normal_part < 0) rendered_ -= normal_part * model.normal;
  const Vec3 desired = workspace_.ForceToDevice(rendered_);
  const Vec3 out = safety_.Filter(desired, dt, t - model.published_at, pose.connected);
  device_.Command(out, Vec3::Zero());
  if (feedback_ != nullptr) {
    HapticFeedback& f = feedback_->back();
    f.tool = x;
    f.force = -force;
    f.contact_vertex = model.active ? model.contact_vertex : -1;
    f.time = t;
    feedback_->Publish();
  }
  return out;
}

}  // namespace gipsi
