#pragma once
/// @file
/// Physical quantities with units in scene files. A quantity is either a plain number, taken in
/// the SI unit the key documents, or a string "VALUE UNIT" ("0.17 S/m", "1 uF/cm^2",
/// "1400 1/cm", "0.01 ms", "52 uA/uF") converted to that SI unit. Units are parsed by UDUNITS-2
/// (Unidata), so prefixes, products, quotients and powers work as a physicist writes them;
/// a unit of another dimension is rejected with an error naming the file, the JSON path, the
/// unit given and the dimension expected.

#include <string>
#include <string_view>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The value of `node` in the SI unit `si_unit` (a UDUNITS-2 expression such as "S/m",
/// "F/m^2", "1/m", "s", "A/m^3", "V"). Throws InputError naming the JSON path for anything that
/// is not a finite number or a "VALUE UNIT" string whose unit converts to `si_unit`.
double ReadQuantity(const JsonNode& node, std::string_view si_unit);

/// As ReadQuantity, and the result must be > 0 (or >= 0 with `allow_zero`).
double ReadPositiveQuantity(const JsonNode& node, std::string_view si_unit,
                            bool allow_zero = false);

/// A quantity as written, not converted: a plain number (empty `unit`) or "VALUE UNIT".
struct WrittenQuantity {
  double value = 0;
  std::string unit;
};
/// Reads `node` as a finite number or a "VALUE UNIT" string with a finite value (the unit is
/// not checked). Throws InputError at the node otherwise: `expected` says what was expected,
/// `hint_unit` is the unit shown in the example of a value without its unit.
WrittenQuantity ReadWrittenQuantity(const JsonNode& node, std::string_view expected,
                                    std::string_view hint_unit);

/// Factor f such that a value in `unit` times f is in `si_unit`; throws std::invalid_argument if
/// either does not parse or they are not convertible (used by tests and ReadQuantity).
double UnitFactor(std::string_view unit, std::string_view si_unit);

}  // namespace gipsi
GIPSI_EXPORT_END
