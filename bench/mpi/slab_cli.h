#pragma once
// The MPI benches' shared command line: the slab's size in hexahedra (--cells NX NY NZ) and a
// parse that exits 2 with CLI11's message on a bad command line (0 after --help).

#include <CLI/CLI.hpp>

#include <array>
#include <cstdlib>

namespace gipsi::bench {

// Adds --cells NX NY NZ (hexahedra along the 20 × 7 × 3 mm slab, 6 tets each) into `cells`.
inline void AddSlabCells(CLI::App& app, std::array<int, 3>& cells) {
  app.add_option("--cells", cells, "Hexahedra along the slab (6 tets each)")
      ->check(CLI::Range(1, 100000));
}

inline void ParseOrExit(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints the message (or the help)
    std::exit(code == 0 ? 0 : 2);
  }
}

}  // namespace gipsi::bench
