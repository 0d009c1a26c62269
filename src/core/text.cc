#include "kincal/text.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <utility>

namespace kincal {
namespace {

constexpr int32_t kEnd = -1;
constexpr int32_t kBadSurrogate = -2;
constexpr int32_t kNone = -3;

}  // namespace

TextLines::TextLines(const std::string& path, std::string_view what, size_t max_line_bytes,
                     int max_lines)
    : path_(path), max_line_bytes_(max_line_bytes), max_lines_(max_lines) {
  const std::string cannot = path + ": cannot open " + std::string(what) + ": ";
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    Fail(cannot + std::strerror(EISDIR));
    return;
  }
  in_.open(path, std::ios::binary);
  if (!in_) {
    Fail(cannot + std::strerror(errno));
    return;
  }
  DetectEncoding();
}

bool TextLines::Fail(std::string message) {
  if (status_.ok()) status_ = Status::Error(std::move(message));
  return false;
}

int TextLines::NextByte() {
  if (held_ > 0) return static_cast<unsigned char>(head_[head_size_ - held_--]);
  const int c = in_.rdbuf()->sbumpc();
  return c == std::char_traits<char>::eof() ? kEnd : c;
}

// A byte-order mark, when there is one, says the encoding and is not part of the text.
// The bytes read to look for it are given back unless they are one (pipes cannot seek).
void TextLines::DetectEncoding() {
  while (head_size_ < sizeof head_) {
    const int c = in_.rdbuf()->sbumpc();
    if (c == std::char_traits<char>::eof()) break;
    head_[head_size_++] = static_cast<char>(c);
  }
  const std::string_view head(head_, head_size_);
  size_t mark = 0;
  if (head.substr(0, 3) == kUtf8Bom) {
    mark = 3;
  } else if (head == std::string_view("\xFF\xFE\0\0", 4) ||
             head == std::string_view("\0\0\xFE\xFF", 4)) {
    Fail(path_ + ": the file is UTF-32 text (its byte-order mark is " + Escaped(head) +
         "): save it as UTF-8 or UTF-16");
  } else if (head.substr(0, 2) == "\xFF\xFE") {
    encoding_ = Encoding::kUtf16Le;
    mark = 2;
  } else if (head.substr(0, 2) == "\xFE\xFF") {
    encoding_ = Encoding::kUtf16Be;
    mark = 2;
  }
  held_ = static_cast<int>(head_size_ - mark);
}

int32_t TextLines::NextCodePoint() {
  if (pending_ != kNone) return std::exchange(pending_, kNone);
  if (encoding_ == Encoding::kUtf8) return NextByte();
  const auto unit = [&]() -> int32_t {
    const int a = NextByte();
    if (a == kEnd) return kEnd;
    const int b = NextByte();
    if (b == kEnd) return kBadSurrogate;  // half a code unit
    return encoding_ == Encoding::kUtf16Le ? (b << 8 | a) : (a << 8 | b);
  };
  const int32_t first = unit();
  if (first < 0xD800 || first > 0xDFFF) return first;
  if (first > 0xDBFF) return kBadSurrogate;  // a low surrogate alone
  const int32_t second = unit();
  if (second < 0xDC00 || second > 0xDFFF) return kBadSurrogate;
  return 0x10000 + ((first - 0xD800) << 10) + (second - 0xDC00);
}

// UTF-8 bytes pass through; a decoded UTF-16 code point is written as UTF-8.
void TextLines::Append(int32_t cp, std::string* line) {
  if (encoding_ == Encoding::kUtf8 || cp < 0x80) {
    line->push_back(static_cast<char>(cp));
  } else if (cp < 0x800) {
    line->push_back(static_cast<char>(0xC0 | cp >> 6));
    line->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else if (cp < 0x10000) {
    line->push_back(static_cast<char>(0xE0 | cp >> 12));
    line->push_back(static_cast<char>(0x80 | (cp >> 6 & 0x3F)));
    line->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else {
    line->push_back(static_cast<char>(0xF0 | cp >> 18));
    line->push_back(static_cast<char>(0x80 | (cp >> 12 & 0x3F)));
    line->push_back(static_cast<char>(0x80 | (cp >> 6 & 0x3F)));
    line->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  }
}

bool TextLines::Next(std::string* line) {
  line->clear();
  if (!status_.ok()) return false;
  const auto where = [&] { return path_ + ":" + std::to_string(line_number_ + 1); };
  int32_t cp = NextCodePoint();
  if (cp == kEnd) return false;
  if (line_number_ >= max_lines_) {
    too_many_lines_ = true;
    return Fail(path_ + ": more than " + std::to_string(max_lines_) +
                " lines, the most read from one file");
  }
  for (; cp != kEnd; cp = NextCodePoint()) {
    if (cp == kBadSurrogate) return Fail(where() + ": broken UTF-16 text (an unpaired surrogate)");
    if (cp == '\n') break;
    if (cp == '\r') {  // CRLF, or a lone CR (classic Mac): the line ends either way
      const int32_t after = NextCodePoint();
      if (after != '\n' && after != kEnd) pending_ = after;
      break;
    }
    if (line->size() >= max_line_bytes_) {
      line_too_long_ = true;
      return Fail(where() + ": line longer than " + std::to_string(max_line_bytes_) +
                  " bytes: not a text file of this kind");
    }
    Append(cp, line);
  }
  ++line_number_;
  return true;
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

std::string ShortNumber(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

StatusOr<std::string> ReadTextFile(const std::string& path, std::string_view what,
                                   size_t max_bytes) {
  // Bounded by its bytes: every line takes one at least, so no line bound is reached first.
  const auto max_lines = static_cast<int>(
      std::min<size_t>(max_bytes + 1, static_cast<size_t>(std::numeric_limits<int>::max())));
  TextLines lines(path, what, max_bytes, max_lines);
  std::string text, line;
  while (text.size() <= max_bytes && lines.Next(&line)) {
    text += line;
    text += '\n';
  }
  // A line longer than the whole bound is a file too large too.
  if (text.size() > max_bytes || lines.line_too_long()) {
    return Status::Error(path + ": " + std::string(what) + " larger than " +
                         std::to_string(max_bytes) + " bytes: not read");
  }
  if (!lines.status().ok()) return lines.status();
  return text;
}

}  // namespace kincal
