#pragma once
/// @file
/// Logging through spdlog. The framework logs through `gipsi::Log()`; applications set the level.
/// Never log from a step's hot path or the haptic loop.

#include <spdlog/spdlog.h>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The framework's logger (stderr, colour when a terminal).
spdlog::logger& Log();

}  // namespace gipsi
GIPSI_EXPORT_END
