#pragma once
/// @file
/// Scene keys shared by the monodomain objects ("Monodomain", "GridMonodomain"); documented in
/// docs/scene-format.md. Quantities are SI numbers or "VALUE UNIT" strings (base/units.h).

#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/registry.h"
#include "gipsi/models/ep/ep_tissue.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Checks that the object's keys are the common ones, the EP tissue keys, or `extra`.
void CheckEpTissueKeys(const ObjectBuildContext& ctx, const std::vector<std::string>& extra = {});

/// Reads cell, conductivity, fibres, surface_to_volume, capacitance, splitting, diffusion,
/// reaction, stimuli, clamps, activation and (if the keys allow it: Monodomain) parallel.
/// Throws InputError naming the JSON path.
EpTissueParams ParseEpTissueParams(const ObjectBuildContext& ctx);

}  // namespace gipsi
GIPSI_EXPORT_END
