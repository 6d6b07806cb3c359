#include "gipsi/models/circulation/valve.h"

#include <algorithm>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {

std::string_view ToString(ValveState state) {
  return state == ValveState::kOpen ? "open" : "closed";
}

ValveEventLog::ValveEventLog(std::size_t capacity) : capacity_(capacity) {
  GIPSI_CHECK(capacity >= 1, "the valve event log needs room for one event");
  ring_.reserve(capacity);
}

void ValveEventLog::Record(const ValveEvent& event) {
  if (ring_.size() < capacity_)
    ring_.push_back(event);
  else
    ring_[static_cast<std::size_t>(total_ % static_cast<std::int64_t>(capacity_))] = event;
  ++total_;
}

std::string ValveEventLog::Inconsistency(int num_valves) const {
  if (ring_.size() > capacity_)
    return fmt::format("{} valve events kept, more than the log's capacity {}", ring_.size(),
                       capacity_);
  if (total_ < 0 || std::min<std::int64_t>(total_, static_cast<std::int64_t>(capacity_)) !=
                        static_cast<std::int64_t>(ring_.size()))
    return fmt::format("{} valve events kept of a total {} (capacity {})", ring_.size(), total_,
                       capacity_);
  for (std::size_t k = 0; k < ring_.size(); ++k) {
    if (ring_[k].state != ValveState::kClosed && ring_[k].state != ValveState::kOpen)
      return fmt::format("valve event {} has no valve state {}", k, int(ring_[k].state));
    if (ring_[k].valve < 0 || ring_[k].valve >= num_valves)
      return fmt::format("valve event {} names valve {} of {}", k, ring_[k].valve, num_valves);
  }
  return {};
}

std::vector<ValveEvent> ValveEventLog::EventsSince(std::int64_t first) const {
  const auto cap = static_cast<std::int64_t>(capacity_);
  const std::int64_t begin = std::max({first, total_ - cap, std::int64_t{0}});
  std::vector<ValveEvent> out;
  out.reserve(static_cast<std::size_t>(std::max<std::int64_t>(total_ - begin, 0)));
  for (std::int64_t k = begin; k < total_; ++k)
    out.push_back(ring_[static_cast<std::size_t>(k % cap)]);
  return out;
}

std::vector<ValveEvent> ValveEventLog::Events() const { return EventsSince(0); }

}  // namespace gipsi
