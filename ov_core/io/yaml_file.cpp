#include "ov_core/io/yaml_file.h"
#include "ov_core/io/csv.h"

#include <fstream>
#include <map>
#include <sstream>

namespace ovton::core {

namespace {

/// Mapping keys must be unique (YAML 1.2 §3.2.1.1); yaml-cpp keeps both and lookups see only the first, so a config
/// that sets a key twice would silently ignore the second value the user meant.
void check_unique_keys(const YAML::Node &n, const std::string &file) {
  if (n.IsMap()) {
    std::map<std::string, long> seen;
    for (const auto &kv : n) {
      if (kv.first.IsScalar()) {
        const std::string key = kv.first.Scalar();
        const auto [it, fresh] = seen.emplace(key, yaml_line(kv.first));
        if (!fresh)
          throw DataError(file, yaml_line(kv.first),
                          "duplicate key '" + key + "' (first at line " + std::to_string(it->second) + ")");
      }
      check_unique_keys(kv.second, file);
    }
  } else if (n.IsSequence()) {
    for (const auto &x : n)
      check_unique_keys(x, file);
  }
}

} // namespace

long yaml_line(const YAML::Node &n) {
  if (!n.IsDefined())
    return 0;
  const YAML::Mark m = n.Mark();
  return m.is_null() ? 0 : m.line + 1;
}

YAML::Node parse_yaml_text(const std::string &text_in, const std::string &file) {
  std::string text = text_in;
  if (text.rfind(kUtf8Bom, 0) == 0)
    text.erase(0, 3);
  // OpenCV writes "%YAML:1.0" (EuRoC's sensor.yaml files), a directive yaml-cpp rejects; blanked so lines still match.
  if (text.rfind("%YAML", 0) == 0)
    text.erase(0, text.find('\n'));
  YAML::Node n;
  try {
    n = YAML::Load(text);
  } catch (const YAML::Exception &e) {
    throw DataError(file, e.mark.is_null() ? 0 : e.mark.line + 1, "unreadable YAML: " + e.msg);
  }
  if (!n.IsMap())
    throw DataError(file, "expected a YAML mapping at the top level");
  check_unique_keys(n, file);
  return n;
}

YAML::Node load_yaml_file(const std::string &file) {
  require_file(file);
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw DataError(file, "cannot open for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_yaml_text(ss.str(), file);
}

} // namespace ovton::core
