#include "gipsi/io/obj_io.h"

#include <cstdint>
#include <string>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/mesh_builder.h"
#include "gipsi/io/text_reader.h"

namespace gipsi {

Mesh ReadObj(const std::filesystem::path& path) {
  internal::TextReader r = internal::TextReader::FromFile(path);
  internal::MeshBuilder b;
  std::int64_t max_index = 0;  // largest positive index, checked at the end
  int max_index_line = 0;
  std::vector<int> corners;
  std::string_view line;
  while (r.NextContentLine(&line, '#')) {
    auto t = internal::SplitTokens(line);
    if (t[0] == "v") {
      if (t.size() < 4)
        r.Fail(fmt::format("expected a vertex 'v x y z', got {} coordinates", t.size() - 1));
      b.AddNode(r.ToFinite(t[1], "an x coordinate"), r.ToFinite(t[2], "a y coordinate"),
                r.ToFinite(t[3], "a z coordinate"));
    } else if (t[0] == "f") {
      if (t.size() < 4)
        r.Fail(fmt::format("expected a face with at least 3 corners, got {}", t.size() - 1));
      corners.clear();
      for (std::size_t k = 1; k < t.size(); ++k) {
        std::string_view ref = t[k].substr(0, t[k].find('/'));
        std::int64_t i = r.ToInt(ref, "a vertex index");
        if (i == 0) r.Fail("vertex index 0 is invalid (OBJ indices start at 1)");
        if (i < 0) {
          i += b.num_nodes() + 1;
          if (i < 1)
            r.Fail(fmt::format("relative vertex index {} points before the first vertex", ref));
        }
        if (i > std::int64_t(INT32_MAX)) r.Fail(fmt::format("vertex index {} is too large", i));
        if (i > max_index) {
          max_index = i;
          max_index_line = r.line();
        }
        for (int c : corners)
          if (c == i - 1) r.Fail(fmt::format("face repeats vertex {}", i));
        corners.push_back(static_cast<int>(i - 1));
      }
      for (std::size_t k = 1; k + 1 < corners.size(); ++k)
        b.AddTriangle(corners[0], corners[k], corners[k + 1]);
    }
  }
  if (max_index > b.num_nodes()) {
    ThrowInputError(r.source(), fmt::format("line {}", max_index_line),
                    fmt::format("vertex index {} out of range: the file has {} vertices", max_index,
                                b.num_nodes()));
  }
  return b.Build(r.source());
}

void WriteObj(const std::filesystem::path& path, const Points& nodes, const Triangles& triangles) {
  GIPSI_CHECK(
      triangles.size() == 0 || (triangles.minCoeff() >= 0 && triangles.maxCoeff() < nodes.cols()),
      "triangle node index out of range [0, {})", nodes.cols());
  std::string out = "# written by GiPSi\n";
  out.reserve(static_cast<std::size_t>(60 * nodes.cols() + 30 * triangles.cols()));
  for (Index i = 0; i < nodes.cols(); ++i)
    out += fmt::format("v {} {} {}\n", nodes(0, i), nodes(1, i), nodes(2, i));
  for (Index t = 0; t < triangles.cols(); ++t)
    out +=
        fmt::format("f {} {} {}\n", triangles(0, t) + 1, triangles(1, t) + 1, triangles(2, t) + 1);
  internal::WriteFileBytes(path, out);
}

}  // namespace gipsi
