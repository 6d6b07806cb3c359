#pragma once
/// @file
/// Internal helper of the VTK readers (vtk_legacy_reader.h and vtu_reader.h: the whole file and
/// one process's block): the data types a legacy or XML file names and how binary values load.
/// Not part of the public API.

#include <cctype>
#include <cstdint>
#include <string>
#include <string_view>

#include "gipsi/io/text_reader.h"

namespace gipsi::internal {

inline std::string VtkLower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

/// A VTK legacy data type.
struct VtkDataType {
  int bytes = 0;  // 0: unknown
  bool is_float = false;
  bool is_signed = true;
};

/// The type a legacy file names ("float", "vtktypeint64", ...); bytes 0 for an unknown name.
inline VtkDataType ParseVtkDataType(std::string_view name) {
  const std::string n = VtkLower(name);
  if (n == "float" || n == "vtktypefloat32") return {4, true, true};
  if (n == "double" || n == "vtktypefloat64") return {8, true, true};
  if (n == "char" || n == "vtktypeint8") return {1, false, true};
  if (n == "unsigned_char" || n == "vtktypeuint8" || n == "bit") return {1, false, false};
  if (n == "short" || n == "vtktypeint16") return {2, false, true};
  if (n == "unsigned_short" || n == "vtktypeuint16") return {2, false, false};
  if (n == "int" || n == "vtktypeint32") return {4, false, true};
  if (n == "unsigned_int" || n == "vtktypeuint32") return {4, false, false};
  if (n == "long" || n == "vtktypeint64" || n == "vtkidtype") return {8, false, true};
  if (n == "unsigned_long" || n == "vtktypeuint64") return {8, false, false};
  return {};
}

/// The type a VTK XML file names ("Float32", "UInt8", ...); bytes 0 for an unknown name.
inline VtkDataType ParseVtuDataType(std::string_view name) {
  if (name == "Float32") return {4, true, true};
  if (name == "Float64") return {8, true, true};
  if (name == "Int8") return {1, false, true};
  if (name == "UInt8") return {1, false, false};
  if (name == "Int16") return {2, false, true};
  if (name == "UInt16") return {2, false, false};
  if (name == "Int32") return {4, false, true};
  if (name == "UInt32") return {4, false, false};
  if (name == "Int64") return {8, false, true};
  if (name == "UInt64") return {8, false, false};
  return {};
}

/// Largest expansion zlib can achieve (deflate's limit is about 1032:1): a VTK XML array whose
/// declared size exceeds its compressed bytes by more is refused before anything is allocated.
constexpr std::uint64_t kMaxZlibRatio = 1100;

/// The binary value of a real `type` at `p` (`swap`: the host is little-endian).
inline double LoadVtkReal(const char* p, VtkDataType type, bool swap) {
  return type.bytes == 4 ? double(LoadScalar<float>(p, swap)) : LoadScalar<double>(p, swap);
}

/// The binary value of an integer `type` at `p`.
inline std::int64_t LoadVtkInt(const char* p, VtkDataType type, bool swap) {
  switch (type.bytes) {
    case 1:
      return type.is_signed ? LoadScalar<std::int8_t>(p, swap) : LoadScalar<std::uint8_t>(p, swap);
    case 2:
      return type.is_signed ? LoadScalar<std::int16_t>(p, swap)
                            : LoadScalar<std::uint16_t>(p, swap);
    case 4:
      return type.is_signed ? LoadScalar<std::int32_t>(p, swap)
                            : LoadScalar<std::uint32_t>(p, swap);
    default:
      return LoadScalar<std::int64_t>(p, swap);
  }
}

}  // namespace gipsi::internal
