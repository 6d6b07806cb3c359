#include "gipsi/io/stl_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/mesh_builder.h"
#include "gipsi/io/text_reader.h"

namespace gipsi {
namespace {

using internal::TextReader;

struct CellKey {
  std::int64_t x, y, z;
  bool operator==(const CellKey&) const = default;
};

struct CellKeyHash {
  std::size_t operator()(const CellKey& k) const {
    auto h = static_cast<std::uint64_t>(k.x) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(k.y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(k.z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h);
  }
};

/// Welds the corners (x y z per corner, 3 corners per triangle) into `b`'s nodes and adds the
/// non-degenerate triangles. Corners within `relative_tolerance` times the bounding-box
/// diagonal of each other share a vertex (greedy: the first corner of a cluster represents it).
void WeldInto(const std::vector<double>& corners, double relative_tolerance,
              internal::MeshBuilder& b) {
  const std::size_t n = corners.size() / 3;
  if (n == 0) return;
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (std::size_t c = 0; c < n; ++c) {
    Vec3 p(corners[3 * c], corners[3 * c + 1], corners[3 * c + 2]);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double diagonal = (hi - lo).norm();
  const double max_abs = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
  const double tol = relative_tolerance * diagonal;
  // Cells at least `tol` wide (so that the 27 neighbouring cells hold every candidate) and wide
  // enough that cell coordinates fit comfortably in 64-bit integers.
  double h = std::max({tol, 1e-9 * diagonal, 1e-12 * max_abs});
  if (!(h > 0)) h = 1.0;
  const int reach = tol > 0 ? 1 : 0;
  std::unordered_map<CellKey, std::vector<int>, CellKeyHash> grid;
  grid.reserve(n);
  std::vector<int> vertex(n);
  for (std::size_t c = 0; c < n; ++c) {
    const double* p = &corners[3 * c];
    CellKey key{static_cast<std::int64_t>(std::floor(p[0] / h)),
                static_cast<std::int64_t>(std::floor(p[1] / h)),
                static_cast<std::int64_t>(std::floor(p[2] / h))};
    int found = -1;
    for (int dx = -reach; dx <= reach && found < 0; ++dx)
      for (int dy = -reach; dy <= reach && found < 0; ++dy)
        for (int dz = -reach; dz <= reach && found < 0; ++dz) {
          auto it = grid.find({key.x + dx, key.y + dy, key.z + dz});
          if (it == grid.end()) continue;
          for (int v : it->second) {
            const double* q = &b.coords[3 * std::size_t(v)];
            double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                        (p[2] - q[2]) * (p[2] - q[2]);
            if (d2 <= tol * tol) {
              found = v;
              break;
            }
          }
        }
    if (found < 0) {
      found = b.AddNode(p[0], p[1], p[2]);
      grid[key].push_back(found);
    }
    vertex[c] = found;
  }
  for (std::size_t t = 0; t + 2 < n; t += 3) {
    int a = vertex[t], v1 = vertex[t + 1], v2 = vertex[t + 2];
    if (a != v1 && v1 != v2 && a != v2) b.AddTriangle(a, v1, v2);
  }
}

bool LooksLikeAsciiStl(std::string_view data) {
  for (char ch : data) {
    auto c = static_cast<unsigned char>(ch);
    if (c >= 127 || (c < 32 && c != '\n' && c != '\r' && c != '\t' && c != '\f' && c != '\v'))
      return false;
  }
  return data.find("endsolid") != std::string_view::npos;
}

void ReadBinary(const TextReader& r, std::uint32_t count, std::vector<double>& corners) {
  const bool swap = !internal::HostIsLittleEndian();
  corners.resize(9 * std::size_t(count));
  for (std::size_t t = 0; t < count; ++t) {
    std::size_t at = 84 + 50 * t + 12;
    for (std::size_t k = 0; k < 9; ++k) {
      double v = internal::LoadScalar<float>(r.data().data() + at + 4 * k, swap);
      if (!std::isfinite(v))
        r.FailAtOffset(fmt::format("triangle {} has a non-finite vertex coordinate", t),
                       at + 4 * k);
      corners[9 * t + k] = v;
    }
  }
}

void Expect(TextReader& r, std::string_view keyword) {
  std::string_view token = r.RequireToken(keyword);
  if (token != keyword)
    r.Fail(fmt::format("expected '{}', got {}", keyword, internal::Quote(token)));
}

void ReadAscii(TextReader& r, std::vector<double>& corners) {
  Expect(r, "solid");
  r.SkipRestOfLine();
  std::vector<double> facet;
  for (std::string_view token = r.NextToken(); !token.empty(); token = r.NextToken()) {
    if (token == "endsolid" || token == "solid") {
      r.SkipRestOfLine();
      continue;
    }
    if (token != "facet")
      r.Fail(fmt::format("expected 'facet' or 'endsolid', got {}", internal::Quote(token)));
    Expect(r, "normal");
    for (int k = 0; k < 3; ++k) {
      double ignored = 0;
      std::string_view n = r.RequireToken("a normal component");
      if (!internal::TryParseDouble(n, &ignored))
        r.Fail(fmt::format("expected a normal component, got {}", internal::Quote(n)));
    }
    Expect(r, "outer");
    Expect(r, "loop");
    facet.clear();
    while (r.PeekToken() == "vertex") {
      r.NextToken();
      for (int k = 0; k < 3; ++k) facet.push_back(r.ReadFinite("a vertex coordinate"));
    }
    Expect(r, "endloop");
    if (facet.size() < 9)
      r.Fail(fmt::format("expected at least 3 vertices in a facet, got {}", facet.size() / 3));
    Expect(r, "endfacet");
    for (std::size_t k = 3; k + 3 < facet.size(); k += 3) {
      corners.insert(corners.end(), facet.begin(), facet.begin() + 3);
      corners.insert(corners.end(), facet.begin() + std::ptrdiff_t(k),
                     facet.begin() + std::ptrdiff_t(k + 6));
    }
  }
}

void PutFloat(std::string& out, double v) {
  auto f = static_cast<float>(v);
  char bytes[4];
  std::memcpy(bytes, &f, 4);
  if (!internal::HostIsLittleEndian()) std::reverse(bytes, bytes + 4);
  out.append(bytes, 4);
}

}  // namespace

Mesh ReadStl(const std::filesystem::path& path, const StlReadOptions& options) {
  GIPSI_CHECK(options.weld_tolerance >= 0, "negative weld tolerance {}", options.weld_tolerance);
  TextReader r = TextReader::FromFile(path);
  std::string_view data = r.data();
  std::vector<double> corners;
  bool starts_solid = internal::Trim(data.substr(0, 512)).rfind("solid", 0) == 0;
  std::uint64_t count = 0;
  if (data.size() >= 84)
    count = internal::LoadScalar<std::uint32_t>(data.data() + 80, !internal::HostIsLittleEndian());
  bool size_matches = data.size() >= 84 && data.size() == 84 + 50 * count;
  if (size_matches && !(starts_solid && LooksLikeAsciiStl(data))) {
    ReadBinary(r, static_cast<std::uint32_t>(count), corners);
  } else if (starts_solid) {
    ReadAscii(r, corners);
  } else if (data.size() < 84) {
    ThrowInputError(r.source(), "",
                    fmt::format("expected an STL file: {} bytes is too short for binary STL (84 "
                                "bytes at least) and it does not start with 'solid'",
                                data.size()));
  } else {
    r.FailAtOffset(fmt::format("binary STL declares {} triangles, which needs {} bytes, but the "
                               "file has {} bytes (truncated file?)",
                               count, 84 + 50 * count, data.size()),
                   80);
  }
  internal::MeshBuilder b;
  WeldInto(corners, options.weld_tolerance, b);
  return b.Build(r.source());
}

void WriteStl(const std::filesystem::path& path, const Points& nodes, const Triangles& triangles,
              StlFormat format) {
  GIPSI_CHECK(
      triangles.size() == 0 || (triangles.minCoeff() >= 0 && triangles.maxCoeff() < nodes.cols()),
      "triangle node index out of range [0, {})", nodes.cols());
  auto normal = [&](Index t) -> Vec3 {
    Vec3 n = (nodes.col(triangles(1, t)) - nodes.col(triangles(0, t)))
                 .cross(nodes.col(triangles(2, t)) - nodes.col(triangles(0, t)));
    double len = n.norm();
    return len > 0 ? Vec3(n / len) : Vec3::Zero();
  };
  std::string out;
  if (format == StlFormat::kAscii) {
    out = "solid gipsi\n";
    for (Index t = 0; t < triangles.cols(); ++t) {
      Vec3 n = normal(t);
      out += fmt::format("  facet normal {} {} {}\n    outer loop\n", n.x(), n.y(), n.z());
      for (Index a = 0; a < 3; ++a) {
        auto p = nodes.col(triangles(a, t));
        out += fmt::format("      vertex {} {} {}\n", p.x(), p.y(), p.z());
      }
      out += "    endloop\n  endfacet\n";
    }
    out += "endsolid gipsi\n";
  } else {
    out.reserve(84 + 50 * static_cast<std::size_t>(triangles.cols()));
    std::string header = "binary STL written by GiPSi";
    header.resize(80, ' ');
    out += header;
    auto count = static_cast<std::uint32_t>(triangles.cols());
    char bytes[4];
    std::memcpy(bytes, &count, 4);
    if (!internal::HostIsLittleEndian()) std::reverse(bytes, bytes + 4);
    out.append(bytes, 4);
    for (Index t = 0; t < triangles.cols(); ++t) {
      Vec3 n = normal(t);
      for (int k = 0; k < 3; ++k) PutFloat(out, n[k]);
      for (Index a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) PutFloat(out, nodes(k, triangles(a, t)));
      out.append(2, '\0');
    }
  }
  internal::WriteFileBytes(path, out);
}

}  // namespace gipsi
