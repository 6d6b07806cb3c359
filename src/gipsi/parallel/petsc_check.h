#pragma once
/// @file
/// PETSc error codes as exceptions, for the parallel layer's own sources (not installed API).

#include <petscsys.h>

#include <stdexcept>
#include <string>

namespace gipsi {

/// Thrown when a PETSc or MPI call fails: the call as written and PETSc's own message.
class PetscError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws PetscError naming `call` unless `code` is 0.
inline void CheckPetsc(PetscErrorCode code, const char* call) {
  if (code == 0) return;
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  throw PetscError(std::string("PETSc call failed: ") + call + ": " +
                   (text != nullptr ? text : "unknown error") + " (code " + std::to_string(code) +
                   ")");
}

}  // namespace gipsi

/// Checks a PETSc call: GIPSI_PETSC(VecDuplicate(x, &y));
#define GIPSI_PETSC(call) ::gipsi::CheckPetsc((call), #call)
