/// @file
/// Quantities with units through UDUNITS-2 (libudunits2, Unidata).

#include "gipsi/base/units.h"

#include <fmt/format.h>
#include <udunits2.h>

#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

namespace gipsi {
namespace {

struct UnitFree {
  void operator()(ut_unit* u) const { ut_free(u); }
};
struct ConverterFree {
  void operator()(cv_converter* c) const { cv_free(c); }
};
using UnitPtr = std::unique_ptr<ut_unit, UnitFree>;
using ConverterPtr = std::unique_ptr<cv_converter, ConverterFree>;

// UDUNITS-2 is not thread-safe; every call goes through this lock. The unit system is read once
// from the XML database of the libudunits2-data package and kept for the process's lifetime.
std::mutex& UnitsMutex() {
  static std::mutex mutex;
  return mutex;
}

ut_system* UnitSystem() {
  static ut_system* const system = [] {
    ut_set_error_message_handler(ut_ignore);
    return ut_read_xml(nullptr);
  }();
  if (system == nullptr)
    throw std::runtime_error(
        "cannot read the UDUNITS-2 unit database (package libudunits2-data; or set "
        "UDUNITS2_XML_PATH)");
  return system;
}

UnitPtr Parse(std::string_view text) {
  const std::string s(text);
  UnitPtr unit(ut_parse(UnitSystem(), s.c_str(), UT_UTF8));
  if (!unit) throw std::invalid_argument(fmt::format("'{}' is not a unit", text));
  return unit;
}

// Converts `value` in `unit` to `si_unit`; throws std::invalid_argument for an unknown unit or
// another dimension.
double Convert(double value, std::string_view unit, std::string_view si_unit) {
  std::lock_guard lock(UnitsMutex());
  const UnitPtr from = Parse(unit);
  const UnitPtr to = Parse(si_unit);
  // UDUNITS-2 also calls reciprocal units convertible (m and 1/m): require from/to to be
  // dimensionless instead.
  const UnitPtr ratio(ut_divide(from.get(), to.get()));
  const bool same_dimension =
      ratio && ut_are_convertible(ratio.get(), ut_get_dimensionless_unit_one(UnitSystem())) != 0;
  if (!same_dimension)
    throw std::invalid_argument(
        fmt::format("'{}' cannot be converted to {} (another dimension)", unit, si_unit));
  const ConverterPtr converter(ut_get_converter(from.get(), to.get()));
  if (!converter) throw std::invalid_argument(fmt::format("no conversion from '{}'", unit));
  return cv_convert_double(converter.get(), value);
}

}  // namespace

double UnitFactor(std::string_view unit, std::string_view si_unit) {
  return Convert(1.0, unit, si_unit);
}

WrittenQuantity ReadWrittenQuantity(const JsonNode& node, std::string_view expected,
                                    std::string_view hint_unit) {
  if (node.is_number()) return {node.AsNumber(), {}};
  if (!node.is_string()) node.Expected(expected);
  const std::string text = node.AsString();
  std::size_t pos = 0;
  double value = 0;
  try {
    value = std::stod(text, &pos);
  } catch (const std::exception&) {
    node.Expected(fmt::format("{}, got \"{}\"", expected, text));
  }
  const std::size_t unit_begin = text.find_first_not_of(' ', pos);
  if (unit_begin == std::string::npos || unit_begin == pos)
    node.Expected(
        fmt::format("a value and a unit separated by a space (e.g. \"{} {}\"), got "
                    "\"{}\"",
                    text.substr(0, pos), hint_unit, text));
  if (!std::isfinite(value)) node.Expected(fmt::format("a finite quantity, got \"{}\"", text));
  return {value, text.substr(unit_begin)};
}

double ReadQuantity(const JsonNode& node, std::string_view si_unit) {
  if (node.is_number()) return node.AsNumber();
  const WrittenQuantity q = ReadWrittenQuantity(
      node,
      fmt::format("a number in {} or a string \"VALUE UNIT\" (e.g. \"1.5 {}\")", si_unit, si_unit),
      si_unit);
  const std::string text = node.AsString();
  double result = 0;
  try {
    result = Convert(q.value, q.unit, si_unit);
  } catch (const std::invalid_argument& e) {
    node.Fail(
        fmt::format("\"{}\": {}; expected a quantity convertible to {}", text, e.what(), si_unit));
  } catch (const std::runtime_error& e) {
    node.Fail(e.what());
  }
  if (!std::isfinite(result)) node.Expected(fmt::format("a finite quantity, got \"{}\"", text));
  return result;
}

double ReadPositiveQuantity(const JsonNode& node, std::string_view si_unit, bool allow_zero) {
  const double value = ReadQuantity(node, si_unit);
  if (value < 0 || (value == 0 && !allow_zero))
    node.Expected(fmt::format("a {} quantity, got {} {}", allow_zero ? "non-negative" : "positive",
                              value, si_unit));
  return value;
}

}  // namespace gipsi
