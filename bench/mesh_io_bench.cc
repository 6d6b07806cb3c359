// Reading a Gmsh 4.1 mesh whole (ReadMesh: the file held in memory, one pass) against reading
// one process's block of it (ReadGmshBlock: two streaming passes through a 1 MiB buffer, the
// block kept; io/gmsh_block_reader.h), ASCII and binary, on the 0.2 mm N-version slab (315 k
// tets) written to a temporary file; and the same slab as TetGen files, read whole (ReadTetGen)
// and as one process's block (ReadTetGenBlock: one streaming pass per file, the block kept);
// and the same slab as a legacy VTK unstructured grid, ASCII and binary, read whole
// (ReadVtkLegacy) and as one process's block (ReadVtkLegacyBlock: two streaming passes).
// Run:
//   ./build/release/bench/mesh_io_bench --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "gipsi/geometry/generators.h"
#include "gipsi/io/gmsh_block_reader.h"
#include "gipsi/io/mesh_io.h"
#include "gipsi/io/tetgen_reader.h"
#include "gipsi/io/vtk_legacy_reader.h"

namespace gipsi {
namespace {

// The slab as Gmsh 4.1: its nodes in one block, its tets in one block (no groups).
std::string SlabAsGmsh41(bool binary) {
  const Mesh slab = MakeTetBox(Vec3::Zero(), Vec3(0.020, 0.007, 0.003), {100, 35, 15});
  std::string out = fmt::format("$MeshFormat\n4.1 {} 8\n", binary ? 1 : 0);
  auto raw = [&out](auto v) {
    char bytes[sizeof(v)];
    std::memcpy(bytes, &v, sizeof(v));
    out.append(bytes, sizeof(v));
  };
  auto size = [&](std::uint64_t v) {
    if (binary)
      raw(v);
    else
      out += fmt::format("{} ", v);
  };
  auto end_line = [&] {
    if (!binary) out += '\n';
  };
  if (binary) {
    raw(std::int32_t{1});
    out += '\n';
  }
  out += "$EndMeshFormat\n$Nodes\n";
  const auto n = static_cast<std::uint64_t>(slab.num_nodes());
  const auto m = static_cast<std::uint64_t>(slab.num_tets());
  for (std::uint64_t v : {std::uint64_t{1}, n, std::uint64_t{1}, n}) size(v);
  end_line();
  if (binary) {
    raw(std::int32_t{3});
    raw(std::int32_t{1});
    raw(std::int32_t{0});
    raw(n);
  } else {
    out += fmt::format("3 1 0 {}\n", n);
  }
  for (std::uint64_t i = 1; i <= n; ++i) {
    size(i);
    end_line();
  }
  for (Index i = 0; i < slab.num_nodes(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (binary)
        raw(slab.nodes(k, i));
      else
        out += fmt::format("{:.17g} ", slab.nodes(k, i));
    }
    end_line();
  }
  if (binary) out += '\n';
  out += "$EndNodes\n$Elements\n";
  for (std::uint64_t v : {std::uint64_t{1}, m, std::uint64_t{1}, m}) size(v);
  end_line();
  if (binary) {
    raw(std::int32_t{3});
    raw(std::int32_t{1});
    raw(std::int32_t{4});
    raw(m);
  } else {
    out += fmt::format("3 1 4 {}\n", m);
  }
  for (Index e = 0; e < slab.num_tets(); ++e) {
    size(static_cast<std::uint64_t>(e + 1));
    for (int k = 0; k < 4; ++k) size(static_cast<std::uint64_t>(slab.tets(k, e) + 1));
    end_line();
  }
  if (binary) out += '\n';
  out += "$EndElements\n";
  return out;
}

// The file, written once per process and format.
const std::filesystem::path& SlabFile(bool binary) {
  static const std::filesystem::path files[2] = {
      [] {
        const auto path = std::filesystem::temp_directory_path() /
                          fmt::format("gipsi_mesh_io_bench_{}_ascii.msh", ::getpid());
        std::ofstream(path, std::ios::binary) << SlabAsGmsh41(false);
        return path;
      }(),
      [] {
        const auto path = std::filesystem::temp_directory_path() /
                          fmt::format("gipsi_mesh_io_bench_{}_binary.msh", ::getpid());
        std::ofstream(path, std::ios::binary) << SlabAsGmsh41(true);
        return path;
      }()};
  return files[binary ? 1 : 0];
}

void BM_ReadMeshWhole(benchmark::State& state) {
  const auto& path = SlabFile(state.range(0) != 0);
  Index tets = 0;
  for (auto _ : state) tets = ReadMesh(path).num_tets();
  state.counters["tets"] = static_cast<double>(tets);
  state.counters["MB"] = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
  state.SetLabel(state.range(0) != 0 ? "binary" : "ascii");
}

// Rank 0 of 2's block: the same work as any rank's (both passes read the whole file).
void BM_ReadGmshBlock(benchmark::State& state) {
  const auto& path = SlabFile(state.range(0) != 0);
  std::int64_t tets = 0;
  for (auto _ : state) tets = ReadGmshBlock(path, 0, 2)->tets.cols();
  state.counters["block_tets"] = static_cast<double>(tets);
  state.SetLabel(state.range(0) != 0 ? "binary" : "ascii");
}

// The slab as TetGen files (nodes numbered from 1, no attributes or markers), once per process;
// returns the .node file's path.
const std::filesystem::path& SlabTetGen() {
  static const std::filesystem::path node = [] {
    const Mesh slab = MakeTetBox(Vec3::Zero(), Vec3(0.020, 0.007, 0.003), {100, 35, 15});
    const auto stem = std::filesystem::temp_directory_path() /
                      fmt::format("gipsi_mesh_io_bench_{}_tetgen", ::getpid());
    std::string text = fmt::format("{} 3 0 0\n", slab.num_nodes());
    for (Index i = 0; i < slab.num_nodes(); ++i)
      text += fmt::format("{} {:.17g} {:.17g} {:.17g}\n", i + 1, slab.nodes(0, i), slab.nodes(1, i),
                          slab.nodes(2, i));
    std::ofstream(std::filesystem::path(stem).concat(".node"), std::ios::binary) << text;
    text = fmt::format("{} 4 0\n", slab.num_tets());
    for (Index e = 0; e < slab.num_tets(); ++e)
      text += fmt::format("{} {} {} {} {}\n", e + 1, slab.tets(0, e) + 1, slab.tets(1, e) + 1,
                          slab.tets(2, e) + 1, slab.tets(3, e) + 1);
    std::ofstream(std::filesystem::path(stem).concat(".ele"), std::ios::binary) << text;
    return std::filesystem::path(stem).concat(".node");
  }();
  return node;
}

void BM_ReadTetGenWhole(benchmark::State& state) {
  const auto& path = SlabTetGen();
  Index tets = 0;
  for (auto _ : state) tets = ReadTetGen(path).num_tets();
  state.counters["tets"] = static_cast<double>(tets);
}

// Rank 0 of 2's block: the same work as any rank's (every line of both files is read).
void BM_ReadTetGenBlock(benchmark::State& state) {
  const auto& path = SlabTetGen();
  Index tets = 0;
  for (auto _ : state) tets = ReadTetGenBlock(path, 0, 2).tets.cols();
  state.counters["block_tets"] = static_cast<double>(tets);
}

// The slab as a legacy VTK unstructured grid (classic cell layout, big-endian when binary),
// once per process and kind.
const std::filesystem::path& SlabVtk(bool binary) {
  auto write = [](bool binary) {
    const Mesh slab = MakeTetBox(Vec3::Zero(), Vec3(0.020, 0.007, 0.003), {100, 35, 15});
    const bool swap = [] {
      const std::uint16_t one = 1;
      unsigned char first = 0;
      std::memcpy(&first, &one, 1);
      return first == 1;
    }();
    std::string out =
        fmt::format("# vtk DataFile Version 3.0\nslab\n{}\nDATASET UNSTRUCTURED_GRID\n",
                    binary ? "BINARY" : "ASCII");
    auto put = [&](auto v) {
      char bytes[sizeof(v)];
      std::memcpy(bytes, &v, sizeof(v));
      if (swap) std::reverse(bytes, bytes + sizeof(v));
      out.append(bytes, sizeof(v));
    };
    out += fmt::format("POINTS {} double\n", slab.num_nodes());
    for (Index i = 0; i < slab.num_nodes(); ++i) {
      for (int k = 0; k < 3; ++k) {
        if (binary)
          put(slab.nodes(k, i));
        else
          out += fmt::format("{:.17g} ", slab.nodes(k, i));
      }
      if (!binary) out += "\n";
    }
    out += fmt::format("\nCELLS {} {}\n", slab.num_tets(), 5 * slab.num_tets());
    for (Index e = 0; e < slab.num_tets(); ++e) {
      if (binary) {
        put(std::int32_t{4});
        for (int k = 0; k < 4; ++k) put(static_cast<std::int32_t>(slab.tets(k, e)));
      } else {
        out += fmt::format("4 {} {} {} {}\n", slab.tets(0, e), slab.tets(1, e), slab.tets(2, e),
                           slab.tets(3, e));
      }
    }
    out += fmt::format("\nCELL_TYPES {}\n", slab.num_tets());
    for (Index e = 0; e < slab.num_tets(); ++e) {
      if (binary)
        put(std::int32_t{10});
      else
        out += "10\n";
    }
    const auto path =
        std::filesystem::temp_directory_path() /
        fmt::format("gipsi_mesh_io_bench_{}_{}.vtk", ::getpid(), binary ? "binary" : "ascii");
    std::ofstream(path, std::ios::binary) << out;
    return path;
  };
  static const std::filesystem::path ascii = write(false), binary_path = write(true);
  return binary ? binary_path : ascii;
}

void BM_ReadVtkWhole(benchmark::State& state) {
  const auto& path = SlabVtk(state.range(0) != 0);
  Index tets = 0;
  for (auto _ : state) tets = ReadVtkLegacy(path).num_tets();
  state.counters["tets"] = static_cast<double>(tets);
}

// Rank 0 of 2's block: the same work as any rank's (the file is read twice through).
void BM_ReadVtkBlock(benchmark::State& state) {
  const auto& path = SlabVtk(state.range(0) != 0);
  Index tets = 0;
  for (auto _ : state) tets = ReadVtkLegacyBlock(path, 0, 2)->tets.cols();
  state.counters["block_tets"] = static_cast<double>(tets);
}

BENCHMARK(BM_ReadMeshWhole)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadGmshBlock)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadTetGenWhole)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadTetGenBlock)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadVtkWhole)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadVtkBlock)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The temporary files go when the benchmark ends.
struct Cleanup {
  ~Cleanup() {
    std::error_code ignored;
    for (const char* kind : {"ascii", "binary"})
      for (const char* extension : {"msh", "vtk"})
        std::filesystem::remove(
            std::filesystem::temp_directory_path() /
                fmt::format("gipsi_mesh_io_bench_{}_{}.{}", ::getpid(), kind, extension),
            ignored);
    for (const char* extension : {"node", "ele"})
      std::filesystem::remove(
          std::filesystem::temp_directory_path() /
              fmt::format("gipsi_mesh_io_bench_{}_tetgen.{}", ::getpid(), extension),
          ignored);
  }
} cleanup;

}  // namespace
}  // namespace gipsi
