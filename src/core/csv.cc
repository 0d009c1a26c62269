#include "kincal/csv.h"

#include <charconv>
#include <cmath>

namespace kincal {
namespace {

std::string_view TrimBlanks(std::string_view s) {
  const size_t b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) return {};
  const size_t e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

}  // namespace

std::vector<std::string> SplitCsvFields(std::string_view line) {
  std::vector<std::string> fields;
  std::string field;
  bool in_quotes = false;  // inside a quoted field's quotes
  bool quoted = false;     // the field began with a quote: what it holds is kept as it is
  for (size_t k = 0; k <= line.size(); ++k) {
    const bool end = k == line.size();
    const char c = end ? ',' : line[k];
    if (in_quotes && !end) {
      if (c != '"') {
        field += c;
      } else if (k + 1 < line.size() && line[k + 1] == '"') {
        field += '"';
        ++k;
      } else {
        in_quotes = false;
      }
    } else if (c == ',') {
      fields.emplace_back(quoted ? std::string(field) : std::string(TrimBlanks(field)));
      field.clear();
      in_quotes = quoted = false;
    } else if (c == '"' && !quoted && TrimBlanks(field).empty()) {
      field.clear();
      in_quotes = quoted = true;
    } else if (!(quoted && (c == ' ' || c == '\t'))) {
      field += c;  // after a closing quote, only blanks are dropped: anything else is named
    }
  }
  return fields;
}

bool ParseFiniteNumber(std::string_view text, double* value) {
  if (text.size() > 1 && text[0] == '+' && text[1] != '-' && text[1] != '+') text.remove_prefix(1);
  const char* end = text.data() + text.size();
  const auto [stop, ec] = std::from_chars(text.data(), end, *value);
  return ec == std::errc() && stop == end && std::isfinite(*value);
}

}  // namespace kincal
