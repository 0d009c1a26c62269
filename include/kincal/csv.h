// The fields of a CSV line and the numbers in them, as spreadsheets and scripts write them:
// spaces around a field, a field in double quotes (RFC 4180: "" inside is one quote, and a
// comma inside is part of the field), a number with a leading '+'.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace kincal {

// The comma-separated fields of `line`, each without the spaces and tabs around it and,
// when quoted, without its quotes. A quote left open runs to the end of the line.
std::vector<std::string> SplitCsvFields(std::string_view line);

// A finite number written in full (decimal or scientific, an optional leading '+' or '-');
// false for anything else, NaN and infinities included.
bool ParseFiniteNumber(std::string_view text, double* value);

}  // namespace kincal
