#include "ov_core/io/csv.h"
#include "ov_core/types/errors.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <unistd.h>

namespace ovton::core {

void require_file(const std::string &file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec))
    throw DataError(file, "file not found");
  if (!std::filesystem::is_regular_file(file, ec))
    throw DataError(file, "not a regular file");
}

void require_writable(const std::string &file) {
  namespace fs = std::filesystem;
  if (file.empty())
    throw UsageError("empty output path");
  if (file == "-") // not a file named '-' beside the user's data: say that standard output is not an output here
    throw UsageError("'-' (standard output) cannot take this output: give a file name");
  std::error_code ec;
  const fs::path p(file);
  if (fs::is_directory(p, ec))
    throw DataError(file, "is a folder, not a file that can be written");
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw DataError(file, "cannot be written: folder " + dir.string() + " does not exist");
  const bool exists = fs::exists(p, ec);
  if (::access((exists ? p : dir).c_str(), W_OK) != 0)
    throw DataError(file, exists ? "cannot be written: no permission to overwrite it"
                                 : "cannot be written: no permission to create files in " + dir.string());
}

std::string join_path(const std::string &a, const std::string &b) {
  return (std::filesystem::path(a) / std::filesystem::path(b)).string();
}

TextTableReader::TextTableReader(const std::string &file, char sep) : file_(file), sep_(sep) {
  require_file(file);
  in_.open(file);
  if (!in_)
    throw DataError(file, "cannot open for reading");
}

static bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

/// Narrows [b, e) of s to leave out the blanks at either end.
static void trim_range(const std::string &s, size_t &b, size_t &e) {
  while (b < e && is_blank(s[b]))
    ++b;
  while (e > b && is_blank(s[e - 1]))
    --e;
}

bool TextTableReader::next(std::vector<std::string> &fields) {
  // The line and the fields' strings are reused from row to row: an IMU log has tens of thousands of rows, and a
  // fresh string per number (too long for the small-string buffer) was a measurable part of a short run.
  std::string &raw = line_buf_;
  while (std::getline(in_, raw)) {
    ++line_;
    // A UTF-8 byte order mark (spreadsheet exports) is not part of the first field.
    if (line_ == 1 && raw.rfind(kUtf8Bom, 0) == 0)
      raw.erase(0, 3);
    size_t b = 0, e = raw.size();
    trim_range(raw, b, e);
    if (b == e)
      continue;
    // '#' comments anywhere; a header line without '#' (e.g. "timestamp_ns,px,...") only before the first row.
    if (raw[b] == '#' || (!seen_data_ && std::isalpha(static_cast<unsigned char>(raw[b])))) {
      comments_.push_back(raw.substr(b, e - b));
      continue;
    }
    seen_data_ = true;
    size_t n = 0;
    const auto put = [&](size_t from, size_t to) {
      if (n == fields.size())
        fields.emplace_back();
      fields[n++].assign(raw, from, to - from);
    };
    if (sep_ == ' ') {
      size_t i = b;
      while (i < e) {
        while (i < e && (raw[i] == ' ' || raw[i] == '\t'))
          ++i;
        size_t j = i;
        while (j < e && raw[j] != ' ' && raw[j] != '\t')
          ++j;
        if (j > i)
          put(i, j);
        i = j;
      }
    } else {
      size_t start = b;
      while (true) {
        const size_t pos = raw.find(sep_, start);
        const size_t end = pos == std::string::npos || pos > e ? e : pos;
        size_t fb = start, fe = end; // each field without the blanks around it
        trim_range(raw, fb, fe);
        put(fb, fe);
        if (end == e)
          break;
        start = end + 1;
      }
    }
    fields.resize(n);
    return true;
  }
  if (in_.bad())
    fail("read error");
  return false;
}

void TextTableReader::fail(const std::string &msg) const {
  throw DataError(file_, line_, msg);
}

int64_t TextTableReader::to_int64(const std::string &field, const char *what) const {
  if (field.empty())
    fail(std::string("empty ") + what);
  // std::from_chars: no locale, no allocation; a leading '+' is accepted as strtoll did.
  const char *first = field.data() + (field[0] == '+' && field.size() > 1 && field[1] != '-' ? 1 : 0);
  const char *last = field.data() + field.size();
  int64_t v = 0;
  const auto [ptr, ec] = std::from_chars(first, last, v);
  if (ec == std::errc::result_out_of_range)
    fail(std::string("bad ") + what + " '" + field + "' (expected an integer)");
  if (ec != std::errc() || ptr != last)
    fail(std::string("bad ") + what + " '" + field + "' (expected an integer)");
  return v;
}

double TextTableReader::to_double(const std::string &field, const char *what) const {
  if (field.empty())
    fail(std::string("empty ") + what);
  const char *first = field.data() + (field[0] == '+' && field.size() > 1 && field[1] != '-' ? 1 : 0);
  const char *last = field.data() + field.size();
  double v = 0;
  const auto [ptr, ec] = std::from_chars(first, last, v);
  // Out of range: strtod gave ±inf or a denormal/0 there; the first is non-finite (refused below), the second a
  // number to keep.
  if (ec == std::errc::result_out_of_range) {
    char *end = nullptr;
    v = std::strtod(field.c_str(), &end);
  } else if (ec != std::errc() || ptr != last) {
    // from_chars does not read what strtod also took: hexadecimal floats, "inf"/"nan" spelled otherwise. Those are
    // either refused below or not numbers a dataset holds; anything else is not a number.
    char *end = nullptr;
    v = std::strtod(field.c_str(), &end);
    if (*end != '\0')
      fail(std::string("bad ") + what + " '" + field + "' (expected a number)");
  }
  if (!std::isfinite(v))
    fail(std::string("non-finite ") + what + " '" + field + "'");
  return v;
}

} // namespace ovton::core
