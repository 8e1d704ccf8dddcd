#include "ov_msckf_ton/core/td_mode.h"
#include "ov_core/types/errors.h"

namespace ovton::msckf {

namespace {
const char *const kModeNames[] = {"off", "sr", "sir", "fvon", "tpn", "ton", "oracle", "drift"};
const char *const kProcessNames[] = {"auto", "constant", "random_walk", "drift", "tpn"};
} // namespace

const std::vector<TdMode> &all_td_modes() {
  static const std::vector<TdMode> m = {TdMode::Off, TdMode::Sr,  TdMode::Sir,    TdMode::Fvon,
                                        TdMode::Tpn, TdMode::Ton, TdMode::Oracle, TdMode::Drift};
  return m;
}

std::string to_string(TdMode m) {
  return kModeNames[static_cast<int>(m)];
}

std::vector<std::string> all_td_mode_names() {
  std::vector<std::string> names;
  for (TdMode m : all_td_modes())
    names.push_back(to_string(m));
  return names;
}

TdMode parse_td_mode(const std::string &s) {
  for (TdMode m : all_td_modes())
    if (to_string(m) == s)
      return m;
  throw ovton::core::UsageError("unknown time-offset mode '" + s +
                                "' (expected off, sr, sir, fvon, tpn, ton, oracle or drift)");
}

std::string to_string(TdProcess p) {
  return kProcessNames[static_cast<int>(p)];
}

TdProcess parse_td_process(const std::string &s) {
  for (int i = 0; i < 5; ++i)
    if (s == kProcessNames[i])
      return static_cast<TdProcess>(i);
  throw ovton::core::UsageError("unknown time-offset process '" + s +
                                "' (expected auto, constant, random_walk, drift or tpn)");
}

TdProcess resolve_td_process(TdMode m, TdProcess configured) {
  if (!estimates_td(m))
    return TdProcess::Constant;
  if (configured != TdProcess::Auto)
    return configured;
  if (m == TdMode::Tpn || m == TdMode::Ton)
    return TdProcess::Tpn;
  if (m == TdMode::Drift)
    return TdProcess::Drift;
  return TdProcess::Constant;
}

ModeSpec parse_mode_spec(const std::string &s) {
  ModeSpec spec;
  spec.name = s;
  const auto plus = s.find('+');
  spec.mode = parse_td_mode(s.substr(0, plus));
  if (plus != std::string::npos) {
    spec.process = parse_td_process(s.substr(plus + 1));
    if (!estimates_td(spec.mode))
      throw ovton::core::UsageError("mode '" + s + "': " + to_string(spec.mode) +
                                    " does not estimate t_d, so it has no "
                                    "process to choose");
  }
  return spec;
}

} // namespace ovton::msckf
