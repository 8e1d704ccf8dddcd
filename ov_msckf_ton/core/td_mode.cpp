#include "ov_msckf_ton/core/td_mode.h"
#include "ov_core/types/errors.h"

namespace ov_msckf_ton {

namespace {
const char *const kNames[] = {"off", "sr", "sir", "fvon", "tpn", "ton", "oracle"};
}

const std::vector<TdMode> &all_td_modes() {
  static const std::vector<TdMode> m = {TdMode::Off, TdMode::Sr,  TdMode::Sir,   TdMode::Fvon,
                                        TdMode::Tpn, TdMode::Ton, TdMode::Oracle};
  return m;
}

std::string to_string(TdMode m) {
  return kNames[static_cast<int>(m)];
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
  throw ov_core::UsageError("unknown time-offset mode '" + s + "' (expected off, sr, sir, fvon, tpn, ton or oracle)");
}

} // namespace ov_msckf_ton
