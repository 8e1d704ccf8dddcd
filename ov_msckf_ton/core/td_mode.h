#pragma once
// The time-offset strategies. The strings are the same in the CLI, configs, CSV file names and tables.
#include <string>
#include <vector>

namespace ov_msckf_ton {

enum class TdMode { Off, Sr, Sir, Fvon, Tpn, Ton, Oracle };

TdMode parse_td_mode(const std::string &s); ///< throws ov_core::UsageError naming the valid modes
std::string to_string(TdMode m);
const std::vector<TdMode> &all_td_modes();
/// The mode strings, in the order of all_td_modes() (for option parsing and listings).
std::vector<std::string> all_td_mode_names();

/// Modes that shift observations on the image plane (paper eq. 1–2).
inline bool uses_sir(TdMode m) {
  return m == TdMode::Sir || m == TdMode::Fvon || m == TdMode::Tpn || m == TdMode::Ton;
}
inline bool uses_fvon(TdMode m) {
  return m == TdMode::Fvon || m == TdMode::Ton;
}
inline bool uses_tpn(TdMode m) {
  return m == TdMode::Tpn || m == TdMode::Ton;
}

} // namespace ov_msckf_ton
