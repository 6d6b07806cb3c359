#pragma once
/// @file
/// Object paths for messages: a part of an aggregate is called "heart.muscle" in every message,
/// as on the command line and in the viewer, while its own name ("muscle") stays its key.

#include <string>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// While alive, objects and connectors constructed on this thread are parts of the object at
/// `owner_path` (e.g. "heart"): their path() is "heart.<name>". Aggregate builders open one
/// around building their parts; scopes nest (a part that is itself an aggregate opens its own).
class ObjectPathScope {
 public:
  explicit ObjectPathScope(const std::string& owner_path);
  ~ObjectPathScope();
  ObjectPathScope(const ObjectPathScope&) = delete;
  ObjectPathScope& operator=(const ObjectPathScope&) = delete;

 private:
  std::string previous_;
};

/// `name` as an object or connector constructed now is called in messages: prefixed by the
/// path of the innermost ObjectPathScope ("heart.muscle"), or `name` outside any scope.
[[nodiscard]] std::string ScopedObjectPath(const std::string& name);

}  // namespace gipsi
GIPSI_EXPORT_END
