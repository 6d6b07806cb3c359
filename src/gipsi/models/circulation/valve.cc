#include "gipsi/models/circulation/valve.h"

#include <algorithm>

#include "gipsi/base/error.h"

namespace gipsi {

std::string_view ToString(ValveState state) {
  return state == ValveState::kOpen ? "open" : "closed";
}

ValveEventLog::ValveEventLog(std::size_t capacity) : ring_(capacity) {
  GIPSI_CHECK(capacity >= 1, "the valve event log needs room for one event");
}

void ValveEventLog::Record(const ValveEvent& event) {
  ring_[static_cast<std::size_t>(total_ % static_cast<std::int64_t>(ring_.size()))] = event;
  ++total_;
}

std::vector<ValveEvent> ValveEventLog::EventsSince(std::int64_t first) const {
  const auto cap = static_cast<std::int64_t>(ring_.size());
  const std::int64_t begin = std::max({first, total_ - cap, std::int64_t{0}});
  std::vector<ValveEvent> out;
  out.reserve(static_cast<std::size_t>(std::max<std::int64_t>(total_ - begin, 0)));
  for (std::int64_t k = begin; k < total_; ++k)
    out.push_back(ring_[static_cast<std::size_t>(k % cap)]);
  return out;
}

std::vector<ValveEvent> ValveEventLog::Events() const { return EventsSince(0); }

}  // namespace gipsi
