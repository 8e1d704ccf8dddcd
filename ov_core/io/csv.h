#pragma once
// Line-oriented reading of the numeric text tables that datasets are made of (EuRoC CSV, TUM text).
// Every failure names the file and the 1-based line.
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace ovton::core {

/// The UTF-8 byte order mark some editors and spreadsheets put at the start of a text file.
inline constexpr const char *kUtf8Bom = "\xEF\xBB\xBF";

class TextTableReader {
public:
  /// sep: ',' for CSV; ' ' splits on any run of spaces/tabs (TUM text).
  TextTableReader(const std::string &file, char sep);

  /// Next data row (skips blank lines and lines starting with '#'); false at end of file.
  /// The first non-comment line is also reported through header() if it is not numeric.
  bool next(std::vector<std::string> &fields);
  long line() const { return line_; }
  const std::string &file() const { return file_; }
  /// Comment lines seen before the first data row (e.g. the EuRoC header).
  const std::vector<std::string> &comments() const { return comments_; }

  int64_t to_int64(const std::string &field, const char *what) const;
  double to_double(const std::string &field, const char *what) const;
  [[noreturn]] void fail(const std::string &msg) const;

private:
  std::string file_;
  char sep_;
  std::ifstream in_;
  std::string line_buf_;
  long line_ = 0;
  bool seen_data_ = false;
  std::vector<std::string> comments_;
};

/// Throws DataError unless `file` exists and is a regular file.
void require_file(const std::string &file);
/// Throws DataError unless `file` can be created or overwritten: its folder exists and is writable and it is not a
/// folder itself. Checked before a long run, so that a typo in an output path costs nothing. Creates nothing.
void require_writable(const std::string &file);
std::string join_path(const std::string &a, const std::string &b);

} // namespace ovton::core
