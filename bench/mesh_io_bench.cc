// Reading a Gmsh 4.1 mesh whole (ReadMesh: the file held in memory, one pass) against reading
// one process's block of it (ReadGmshBlock: two streaming passes through a 1 MiB buffer, the
// block kept; io/gmsh_block_reader.h), ASCII and binary, on the 0.2 mm N-version slab (315 k
// tets) written to a temporary file; and the same slab as TetGen files, read whole (ReadTetGen)
// and as one process's block (ReadTetGenBlock: one streaming pass per file, the block kept);
// and the same slab as a legacy VTK unstructured grid, ASCII and binary, read whole
// (ReadVtkLegacy) and as one process's block (ReadVtkLegacyBlock: two streaming passes); and
// the same slab as a VTK XML grid, in the layout GiPSi writes (inline base64) and in VTK's
// compressed one (raw appended data, zlib blocks of 32 KiB), read whole (ReadVtu) and as one
// process's block (ReadVtuBlock: each array streamed through its own buffer).
// Run:
//   ./build/release/bench/mesh_io_bench --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "gipsi/geometry/generators.h"
#include "gipsi/io/gmsh_block_reader.h"
#include "gipsi/io/mesh_io.h"
#include "gipsi/io/tetgen_reader.h"
#include "gipsi/io/vtk_legacy_reader.h"
#include "gipsi/io/vtu_block_reader.h"
#include "gipsi/io/vtu_reader.h"
#include "gipsi/io/vtu_writer.h"

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

// VTK's compressed binary block of `data` (UInt64 header: block count, block size, last
// block's size, each block's compressed size; then the zlib blocks), as vtkXMLWriter writes it.
std::string CompressedVtuBlock(std::string_view data) {
  constexpr std::size_t kBlock = 32768;
  std::vector<std::string> blocks;
  for (std::size_t p = 0; p < data.size(); p += kBlock) {
    const std::size_t n = std::min(kBlock, data.size() - p);
    uLongf size = compressBound(static_cast<uLong>(n));
    std::string block(size, '\0');
    compress(reinterpret_cast<Bytef*>(block.data()), &size,
             reinterpret_cast<const Bytef*>(data.data() + p), static_cast<uLong>(n));
    block.resize(size);
    blocks.push_back(std::move(block));
  }
  std::string out;
  auto put = [&](std::uint64_t v) { out.append(reinterpret_cast<const char*>(&v), 8); };
  put(blocks.size());
  put(kBlock);
  put(data.size() % kBlock);
  for (const auto& b : blocks) put(b.size());
  for (const auto& b : blocks) out += b;
  return out;
}

// The slab as a .vtu: GiPSi's own layout (WriteVtu: inline base64), or VTK's compressed one.
const std::filesystem::path& SlabVtu(bool compressed) {
  auto write = [](bool compressed) {
    const Mesh slab = MakeTetBox(Vec3::Zero(), Vec3(0.020, 0.007, 0.003), {100, 35, 15});
    const auto path =
        std::filesystem::temp_directory_path() /
        fmt::format("gipsi_mesh_io_bench_{}_{}.vtu", ::getpid(), compressed ? "binary" : "ascii");
    if (!compressed) {
      WriteVtu(path, slab.nodes, slab.tets, Triangles(3, 0));
      return path;
    }
    std::vector<std::int64_t> conn(slab.tets.data(), slab.tets.data() + slab.tets.size());
    std::vector<std::int64_t> offsets(static_cast<std::size_t>(slab.num_tets()));
    for (std::size_t e = 0; e < offsets.size(); ++e) offsets[e] = 4 * std::int64_t(e + 1);
    const std::string types(offsets.size(), '\x0a');
    auto bytes = [](const auto& v) {
      return std::string_view(reinterpret_cast<const char*>(v.data()),
                              v.size() * sizeof(v.data()[0]));
    };
    const std::string arrays[] = {
        CompressedVtuBlock(std::string_view(reinterpret_cast<const char*>(slab.nodes.data()),
                                            sizeof(double) * slab.nodes.size())),
        CompressedVtuBlock(bytes(conn)), CompressedVtuBlock(bytes(offsets)),
        CompressedVtuBlock(types)};
    std::size_t at[4] = {};
    for (int a = 1; a < 4; ++a) at[a] = at[a - 1] + arrays[a - 1].size();
    std::string out = fmt::format(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
        "byte_order=\"LittleEndian\" header_type=\"UInt64\" "
        "compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid>\n"
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n<Points>\n"
        "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" "
        "offset=\"{}\"/>\n</Points>\n<Cells>\n"
        "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"{}\"/>\n"
        "<DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"{}\"/>\n"
        "<DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{}\"/>\n"
        "</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_",
        slab.num_nodes(), slab.num_tets(), at[0], at[1], at[2], at[3]);
    for (const auto& a : arrays) out += a;
    out += "\n</AppendedData>\n</VTKFile>\n";
    std::ofstream(path, std::ios::binary) << out;
    return path;
  };
  static const std::filesystem::path inline_path = write(false), compressed_path = write(true);
  return compressed ? compressed_path : inline_path;
}

void BM_ReadVtuWhole(benchmark::State& state) {
  const auto& path = SlabVtu(state.range(0) != 0);
  Index tets = 0;
  for (auto _ : state) tets = ReadVtu(path).num_tets();
  state.counters["tets"] = static_cast<double>(tets);
}

// Rank 0 of 2's block: the same work as any rank's (every array is decoded through).
void BM_ReadVtuBlock(benchmark::State& state) {
  const auto& path = SlabVtu(state.range(0) != 0);
  Index tets = 0;
  for (auto _ : state) tets = ReadVtuBlock(path, 0, 2)->tets.cols();
  state.counters["block_tets"] = static_cast<double>(tets);
}

BENCHMARK(BM_ReadMeshWhole)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadGmshBlock)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadTetGenWhole)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadTetGenBlock)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadVtkWhole)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadVtkBlock)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
// Arg 0: GiPSi's inline base64; 1: VTK's compressed appended data.
BENCHMARK(BM_ReadVtuWhole)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadVtuBlock)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The temporary files go when the benchmark ends.
struct Cleanup {
  ~Cleanup() {
    std::error_code ignored;
    for (const char* kind : {"ascii", "binary"})
      for (const char* extension : {"msh", "vtk", "vtu"})
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
