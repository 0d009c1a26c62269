// A text file as other systems' tools save it: Windows (a UTF-8 byte-order mark, CRLF),
// classic Mac and Excel for Mac's "CSV (Macintosh)" (a lone CR), and a spreadsheet's
// "Unicode text" (UTF-16 little-endian with its byte-order mark, CRLF).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace kincal::testing {

inline std::string WindowsText(const std::string& text) {
  std::string out = "\xEF\xBB\xBF";
  for (char ch : text) out += ch == '\n' ? std::string("\r\n") : std::string(1, ch);
  return out;
}

inline std::string MacText(const std::string& text) {
  std::string out;
  for (char ch : text) out += ch == '\n' ? '\r' : ch;
  return out;
}

// ASCII `text` only (each byte one UTF-16 code unit).
inline std::string Utf16Text(const std::string& text) {
  std::string out = "\xFF\xFE";
  for (char ch : WindowsText(text).substr(3)) {
    out += ch;
    out += '\0';
  }
  return out;
}

// The three, each with a name for a test's messages.
inline std::vector<std::pair<const char*, std::string>> OtherSystemsText(const std::string& text) {
  return {
      {"Windows", WindowsText(text)}, {"classic Mac", MacText(text)}, {"UTF-16", Utf16Text(text)}};
}

}  // namespace kincal::testing
