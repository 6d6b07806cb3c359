#pragma once
/// @file
/// Which objects of a scene, or of an aggregate, a distributed run may make in blocks
/// (ObjectBuildContext::in_blocks): the rule the scene loader and aggregates share, read from
/// the JSON before any object is built.

#include <optional>
#include <set>
#include <string>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class TypeRegistry;

/// Whether `node` holds, at any depth, a string that names the object `name` ("name", a dotted
/// path from it: "name.field", "name.part.field", or one of its conditions: "name/clamp").
[[nodiscard]] bool NamesObject(const JsonNode& node, const std::string& name);

/// The members of `objects` (a scene's "objects" or an aggregate's "parts") a distributed run may
/// make in blocks: of a type and with keys it can make so (TypeRegistry::splits_in_blocks), named
/// by no other object (events may name it), and by the members of `connectors` only as
/// TypeRegistry::connector_part_use allows: one that couples parts joins objects all made in
/// blocks from one domain mesh (their "domain"), or none; one that uses only global fields and
/// capabilities, or couples parts split any way, joins any; any other needs its objects whole.
/// Probes, outputs and the schedule's order may name them. Empty when the registry makes nothing in
/// blocks (a serial run). Objects that fail are removed until none does: one object's removal fails
/// the others a part-to-part connector joins it with.
[[nodiscard]] std::set<std::string> InBlocksObjects(const JsonNode& objects,
                                                    const std::optional<JsonNode>& connectors,
                                                    const TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
