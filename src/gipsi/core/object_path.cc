#include "gipsi/core/object_path.h"

#include <utility>

namespace gipsi {

namespace {
thread_local std::string g_owner_path;  // the innermost ObjectPathScope's, or empty
}  // namespace

ObjectPathScope::ObjectPathScope(const std::string& owner_path)
    : previous_(std::exchange(g_owner_path, owner_path)) {}

ObjectPathScope::~ObjectPathScope() { g_owner_path = std::move(previous_); }

std::string ScopedObjectPath(const std::string& name) {
  return g_owner_path.empty() ? name : g_owner_path + "." + name;
}

}  // namespace gipsi
