#include "gipsi/base/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>

namespace gipsi {

spdlog::logger& Log() {
  static std::shared_ptr<spdlog::logger> logger = [] {
    auto l = spdlog::stderr_color_mt("gipsi");
    l->set_pattern("%^[%l]%$ %v");
    return l;
  }();
  return *logger;
}

}  // namespace gipsi
