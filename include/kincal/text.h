// The text files kincal reads, as people's tools write them: line endings of any system
// (LF, CRLF, or the lone CR of classic Mac and of Excel for Mac's "CSV (Macintosh)"), a
// UTF-8 byte-order mark, or UTF-16 text with its byte-order mark (a spreadsheet's "Unicode
// text"), all read as UTF-8 lines; what stays invisible in a bad token is shown escaped in
// errors. Memory stays bounded whatever the file: a line longer than a bound is an error.
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <string_view>

#include "kincal/status.h"

namespace kincal {

// The UTF-8 byte-order mark some editors and spreadsheet programs write first.
inline constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";

// The longest line of a line-by-line text file (a CSV, a points file, an MR.CLAM .dat).
inline constexpr size_t kMaxTextLineBytes = size_t{1} << 16;

// The most lines read from one such file. Past it reading ends with an error, so a file
// that never ends (a pipe, `yes 0,0,0,0`) runs out neither the memory nor the time.
inline constexpr int kMaxTextLines = 5'000'000;

// A text file's lines one at a time. Lines come without their ending, the first without a
// byte-order mark, UTF-16 decoded to UTF-8. Errors (a file that cannot be opened, a line
// longer than the bound, more lines than the bound, UTF-32, a broken UTF-16 surrogate)
// name the file and the line, and end the lines.
class TextLines {
 public:
  // `what` names the file in errors ("poses CSV": "p.csv: cannot open poses CSV: ...").
  TextLines(const std::string& path, std::string_view what,
            size_t max_line_bytes = kMaxTextLineBytes, int max_lines = kMaxTextLines);

  // The next line into *line; false at the end of the file or on an error (status()).
  bool Next(std::string* line);
  // Ok unless opening or reading failed.
  const Status& status() const { return status_; }
  // The 1-based number of the line last returned.
  int line_number() const { return line_number_; }
  // The lines ended at a line longer than the bound (status() says where).
  bool line_too_long() const { return line_too_long_; }
  // The lines ended because the file holds more than `max_lines` of them.
  bool too_many_lines() const { return too_many_lines_; }

 private:
  enum class Encoding { kUtf8, kUtf16Le, kUtf16Be };
  void DetectEncoding();
  int NextByte();
  // The next code point (UTF-8 bytes are passed through one at a time); -1 at the end.
  int32_t NextCodePoint();
  void Append(int32_t code_point, std::string* line);
  bool Fail(std::string message);

  std::string path_;
  std::ifstream in_;
  size_t max_line_bytes_;
  int max_lines_;
  Encoding encoding_ = Encoding::kUtf8;
  char head_[4] = {};  // the first bytes, read to look for a byte-order mark
  size_t head_size_ = 0;
  int held_ = 0;          // how many of them are still to be read as text
  int32_t pending_ = -3;  // a code point read after a lone CR, which begins the next line
  Status status_;
  int line_number_ = 0;
  bool line_too_long_ = false;
  bool too_many_lines_ = false;
};

// `text` with what a terminal would not show written out: \r, \n, \t, \\, and other control
// or non-ASCII bytes as \xNN (so "237.257\r" reads '237.257\r', not '237.257').
std::string Escaped(std::string_view text);

// A number as a message writes it: six significant digits, no trailing zeros ("3600",
// "0.5", "1e-06").
std::string ShortNumber(double v);

// The largest text file read whole (a configuration, a layout, a camera's intrinsics).
inline constexpr size_t kMaxTextFileBytes = size_t{16} << 20;

// The whole of a small text file (a YAML file handed to a parser) as its lines (above),
// each ended by LF, or an error naming the file and `what` it was to be, with errno's
// text: "cam.yaml: cannot open camera intrinsics: No such file or directory". A file larger
// than `max_bytes` is an error too.
StatusOr<std::string> ReadTextFile(const std::string& path, std::string_view what,
                                   size_t max_bytes = kMaxTextFileBytes);

}  // namespace kincal
