#include "ov_core/io/csv.h"
#include "ov_core/types/errors.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <unistd.h>

namespace ov_core {

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

static std::string trim(const std::string &s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos)
    return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

bool TextTableReader::next(std::vector<std::string> &fields) {
  std::string raw;
  while (std::getline(in_, raw)) {
    ++line_;
    // A UTF-8 byte order mark (spreadsheet exports) is not part of the first field.
    if (line_ == 1 && raw.rfind(kUtf8Bom, 0) == 0)
      raw.erase(0, 3);
    const std::string s = trim(raw);
    if (s.empty())
      continue;
    // '#' comments anywhere; a header line without '#' (e.g. "timestamp_ns,px,...") only before the first row.
    if (s[0] == '#' || (!seen_data_ && std::isalpha(static_cast<unsigned char>(s[0])))) {
      comments_.push_back(s);
      continue;
    }
    seen_data_ = true;
    fields.clear();
    if (sep_ == ' ') {
      size_t i = 0;
      while (i < s.size()) {
        while (i < s.size() && (s[i] == ' ' || s[i] == '\t'))
          ++i;
        size_t j = i;
        while (j < s.size() && s[j] != ' ' && s[j] != '\t')
          ++j;
        if (j > i)
          fields.push_back(s.substr(i, j - i));
        i = j;
      }
    } else {
      size_t start = 0;
      while (true) {
        const size_t pos = s.find(sep_, start);
        fields.push_back(trim(s.substr(start, pos == std::string::npos ? std::string::npos : pos - start)));
        if (pos == std::string::npos)
          break;
        start = pos + 1;
      }
    }
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
  errno = 0;
  char *end = nullptr;
  const long long v = std::strtoll(field.c_str(), &end, 10);
  if (*end != '\0' || errno == ERANGE)
    fail(std::string("bad ") + what + " '" + field + "' (expected an integer)");
  return static_cast<int64_t>(v);
}

double TextTableReader::to_double(const std::string &field, const char *what) const {
  if (field.empty())
    fail(std::string("empty ") + what);
  char *end = nullptr;
  const double v = std::strtod(field.c_str(), &end);
  if (*end != '\0')
    fail(std::string("bad ") + what + " '" + field + "' (expected a number)");
  if (!std::isfinite(v))
    fail(std::string("non-finite ") + what + " '" + field + "'");
  return v;
}

} // namespace ov_core
