/// @file
/// The rule of objects made in blocks (in_blocks.h).

#include "gipsi/core/in_blocks.h"

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "gipsi/core/registry.h"

namespace gipsi {
namespace {

// The type name of an object's or a connector's JSON, or empty.
std::string TypeOf(const JsonNode& node) {
  if (!node.is_object()) return {};
  const auto type = node.Find("type");
  return type && type->is_string() ? type->AsString() : std::string();
}

}  // namespace

bool NamesObject(const JsonNode& node, const std::string& name) {
  if (node.is_string()) {
    const std::string& s = node.raw().get_ref<const std::string&>();
    return s == name || (s.size() > name.size() && s.compare(0, name.size(), name) == 0 &&
                         (s[name.size()] == '.' || s[name.size()] == '/'));
  }
  if (node.is_object()) {
    for (const auto& [key, value] : node.Members())
      if (NamesObject(value, name)) return true;
  } else if (node.is_array()) {
    for (const auto& item : node.Items())
      if (NamesObject(item, name)) return true;
  }
  return false;
}

std::set<std::string> InBlocksObjects(const JsonNode& objects,
                                      const std::optional<JsonNode>& connectors,
                                      const TypeRegistry& registry) {
  // Candidates, with their domain mesh if they name one.
  std::map<std::string, std::optional<std::string>> domain;
  if (registry.splits_in_blocks.empty() || !objects.is_object()) return {};
  for (const auto& [name, node] : objects.Members()) {
    const auto rule = registry.splits_in_blocks.find(TypeOf(node));
    if (rule == registry.splits_in_blocks.end() || !rule->second(node)) continue;
    // Events may name it: they set its conditions (on its part's boundary) and uniform values
    // of its fields, which a part takes as the whole object does.
    bool named = false;
    for (const auto& [other, other_node] : objects.Members())
      if (other != name && NamesObject(other_node, name)) named = true;
    if (named) continue;
    const auto mesh = node.Find("domain");
    domain[name] = mesh && mesh->is_string() ? std::optional(mesh->AsString()) : std::nullopt;
  }
  // Each connector: how it uses objects made in blocks, and the objects it names.
  using PartUse = TypeRegistry::PartUse;
  std::vector<std::pair<PartUse, std::vector<std::string>>> links;
  if (connectors && connectors->is_object()) {
    for (const auto& [connector, node] : connectors->Members()) {
      const auto rule = registry.connector_part_use.find(TypeOf(node));
      auto& [use, ends] = links.emplace_back();
      use = rule != registry.connector_part_use.end() ? rule->second(node) : PartUse::kWhole;
      for (const auto& [name, object] : objects.Members())
        if (NamesObject(node, name)) ends.push_back(name);
    }
  }
  for (bool removed = true; removed;) {
    removed = false;
    for (const auto& [use, ends] : links) {
      if (use == PartUse::kGlobal || use == PartUse::kAnyParts) continue;
      const auto first = domain.find(ends.empty() ? std::string() : ends.front());
      const bool alike = use == PartUse::kPartToPart && first != domain.end() &&
                         first->second.has_value() &&
                         std::all_of(ends.begin(), ends.end(), [&](const std::string& end) {
                           const auto it = domain.find(end);
                           return it != domain.end() && it->second == first->second;
                         });
      if (alike) continue;
      for (const std::string& end : ends) removed = domain.erase(end) > 0 || removed;
    }
  }
  std::set<std::string> out;
  for (const auto& [name, mesh] : domain) out.insert(name);
  return out;
}

}  // namespace gipsi
