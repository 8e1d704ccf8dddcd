#pragma once
// Number and string formatting shared by every report writer (tables, JSON, CSV), so that a missing value looks
// the same everywhere: "n/a" in tables, null in JSON, an empty cell in CSV.
#include <string>

namespace ovton::core {

/// Fixed-point with `decimals` digits, or `missing` for NaN/inf.
std::string format_fixed(double v, int decimals, const char *missing = "n/a");
/// A JSON number with 10 significant digits, or null for NaN/inf.
std::string json_number(double v);
/// A JSON string literal (quotes, backslashes and control characters escaped).
std::string json_string(const std::string &s);
/// Full precision (%.9g) for CSV, or an empty cell for NaN/inf (spreadsheets and pandas read it as missing).
std::string csv_number(double v);

} // namespace ovton::core
