#pragma once
// Reading YAML files so that every problem names the file and line: yaml-cpp's own exceptions carry a line but no
// file, accept duplicate keys silently (and `node[key]` then returns the first one while a loop sees both), and a
// value of the wrong kind (a list where a number belongs) escapes as a bare YAML::Exception.
#include "ov_core/types/errors.h"

#include <yaml-cpp/yaml.h>

#include <string>

namespace ovton::core {

/// Parses `file` (a UTF-8 byte order mark and OpenCV's "%YAML:1.0" first line are accepted). Throws DataError with
/// the file and line for a missing/unreadable file, a syntax error, a top level that is not a mapping, or a key that
/// appears twice in one mapping (anywhere in the document).
YAML::Node load_yaml_file(const std::string &file);

/// The same for YAML text already in memory; `file` names it in errors.
YAML::Node parse_yaml_text(const std::string &text, const std::string &file);

/// 1-based line of a node (0 when yaml-cpp has no mark, e.g. a node that does not exist).
long yaml_line(const YAML::Node &n);

/// n.as<T>(), with a DataError naming the file, the node's line and `what` when the value is of the wrong kind.
template <typename T> T yaml_as(const YAML::Node &n, const std::string &file, const std::string &what) {
  try {
    return n.as<T>();
  } catch (const YAML::Exception &e) {
    throw DataError(file, yaml_line(n), "bad value for '" + what + "': " + e.msg);
  }
}

/// Runs f; a YAML::Exception escaping from it (e.g. `node[key]` on a scalar where a mapping was expected) becomes a
/// DataError naming the file and the line yaml-cpp reports.
template <typename F> auto with_yaml_file(const std::string &file, F &&f) -> decltype(f()) {
  try {
    return f();
  } catch (const YAML::Exception &e) {
    throw DataError(file, e.mark.is_null() ? 0 : e.mark.line + 1, "unexpected YAML structure: " + e.msg);
  }
}

} // namespace ovton::core
