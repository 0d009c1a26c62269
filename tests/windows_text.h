// Text as a Windows tool saves it: a UTF-8 byte-order mark first and CRLF line endings
// (issue 34: every text reader must take both).
#pragma once

#include <string>

namespace kincal::testing {

inline std::string WindowsText(const std::string& text) {
  std::string out = "\xEF\xBB\xBF";
  for (char ch : text) out += ch == '\n' ? std::string("\r\n") : std::string(1, ch);
  return out;
}

}  // namespace kincal::testing
