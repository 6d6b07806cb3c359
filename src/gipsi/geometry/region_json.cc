#include "gipsi/geometry/region_json.h"

namespace gipsi {

Region ParseRegion(const JsonNode& node) {
  constexpr const char* kExpected =
      "\"all\" or an object with one of 'box', 'half_space', 'sphere', 'group', 'nodes'";
  if (node.is_string()) {
    if (node.AsString() == "all") return AllRegion{};
    node.Expected(kExpected);
  }
  if (!node.is_object() || node.size() != 1) node.Expected(kExpected);
  node.CheckKeys({"box", "half_space", "sphere", "group", "nodes"});
  if (auto box = node.Find("box")) {
    box->CheckKeys({"min", "max"});
    BoxRegion r{box->Vector3("min"), box->Vector3("max")};
    if ((r.max - r.min).minCoeff() < 0) box->Fail("expected min <= max in every coordinate");
    return r;
  }
  if (auto half = node.Find("half_space")) {
    half->CheckKeys({"point", "normal"});
    HalfSpaceRegion r{half->Vector3("point"), half->Vector3("normal")};
    if (r.normal.norm() == 0) half->At("normal").Expected("a non-zero vector");
    r.normal.normalize();
    return r;
  }
  if (auto sphere = node.Find("sphere")) {
    sphere->CheckKeys({"center", "radius"});
    return SphereRegion{sphere->Vector3("center"), sphere->Positive("radius")};
  }
  if (auto group = node.Find("group")) return GroupRegion{group->AsString()};
  auto ids = node.At("nodes");
  NodeIdsRegion r;
  for (const auto& item : ids.Items()) {
    auto id = item.AsInt();
    if (id < 0 || id > std::numeric_limits<int>::max()) item.Expected("a node id >= 0");
    r.ids.push_back(static_cast<int>(id));
  }
  return r;
}

}  // namespace gipsi
