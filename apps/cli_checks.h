#pragma once
/// @file
/// Checks of the `gipsi` tool's numeric options with readable messages. CLI11's own
/// (`CLI::PositiveNumber`, `CLI::Range`) print their bounds as 309-digit numbers or "0.000000",
/// and let "nan" through; these read the text themselves, refuse NaN, infinities and trailing
/// characters, and say what was expected, e.g. `--until: expected a positive number of seconds,
/// got '-1'`. A failed check is a CLI::ValidationError, which the tool turns into exit code 2.

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <system_error>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

namespace gipsi::apps {

/// A finite number `x` with `lo < x` (or `lo <= x` if `lo_closed`) and `x <= hi`; `expected`
/// says so in words ("a positive number of seconds").
inline CLI::Validator FiniteNumber(double lo, bool lo_closed, double hi, std::string expected) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double x = 0;
        const char* last = text.data() + text.size();
        const auto [end, error] = std::from_chars(text.data(), last, x);
        const bool ok = error == std::errc() && end == last && std::isfinite(x) &&
                        (lo_closed ? x >= lo : x > lo) && x <= hi;
        return ok ? std::string() : fmt::format("expected {}, got '{}'", expected, text);
      },
      "", "");
}

/// A finite number > 0, e.g. `PositiveNumber("a positive number of seconds")`.
inline CLI::Validator PositiveNumber(std::string expected) {
  return FiniteNumber(0, false, HUGE_VAL, std::move(expected));
}

/// A finite number >= 0.
inline CLI::Validator NonNegativeNumber(std::string expected) {
  return FiniteNumber(0, true, HUGE_VAL, std::move(expected));
}

/// A whole number in [lo, hi].
inline CLI::Validator IntegerIn(std::int64_t lo, std::int64_t hi, std::string expected) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        std::int64_t x = 0;
        const char* last = text.data() + text.size();
        const auto [end, error] = std::from_chars(text.data(), last, x);
        const bool ok = error == std::errc() && end == last && x >= lo && x <= hi;
        return ok ? std::string() : fmt::format("expected {}, got '{}'", expected, text);
      },
      "", "");
}

/// True when this process was started by an MPI launcher with more than one rank: mpirun or
/// mpiexec of Open MPI or MPICH (and Intel MPI), or a Slurm job step (srun; not sbatch alone).
/// Reads the launchers' environment variables only: the tool does not initialise MPI.
inline bool LaunchedWithSeveralRanks() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "SLURM_STEP_NUM_TASKS"}) {
    const char* value = std::getenv(name);
    if (value != nullptr && std::atoi(value) > 1) return true;
  }
  return false;
}

}  // namespace gipsi::apps
