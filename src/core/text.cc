#include "kincal/text.h"

#include <cstdio>

namespace kincal {

void CleanLine(std::string* line, bool first) {
  if (!line->empty() && line->back() == '\r') line->pop_back();
  if (first && std::string_view(*line).substr(0, kUtf8Bom.size()) == kUtf8Bom)
    line->erase(0, kUtf8Bom.size());
}

std::string Escaped(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    switch (c) {
      case '\r':
        out += "\\r";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\\':
        out += "\\\\";
        break;
      default:
        if (c < 0x20 || c >= 0x7f) {
          char hex[5];
          std::snprintf(hex, sizeof hex, "\\x%02X", c);
          out += hex;
        } else {
          out += ch;
        }
    }
  }
  return out;
}

}  // namespace kincal
