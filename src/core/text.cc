#include "kincal/text.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

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

StatusOr<std::string> ReadTextFile(const std::string& path, std::string_view what,
                                   size_t max_bytes) {
  const std::string named = path + ": cannot open " + std::string(what) + ": ";
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(named + std::strerror(errno));
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return Status::Error(named + std::strerror(EISDIR));
  std::string text;
  char buffer[1 << 14];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    text.append(buffer, static_cast<size_t>(in.gcount()));
    if (text.size() > max_bytes) {
      return Status::Error(path + ": " + std::string(what) + " larger than " +
                           std::to_string(max_bytes) + " bytes: not read");
    }
  }
  if (in.bad())
    return Status::Error(path + ": cannot read " + std::string(what) + ": " + std::strerror(errno));
  return text;
}

}  // namespace kincal
