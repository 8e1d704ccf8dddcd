#pragma once
// The time-offset strategies. The strings are the same in the CLI, configs, CSV file names and tables.
// A mode fixes how t_d is observed (not at all, through the clone's time (state-relevant), or on the image plane);
// how it moves between images is the process model (TdProcess, td/td_model.h), chosen by the mode unless the
// config's time_offset.process says otherwise.
#include <string>
#include <vector>

namespace ovton::msckf {

/// `drift` is beyond the paper: sr's observation with t_d and its rate ṫ_d in the state (the paper's eq. 4 as a
/// Kalman process model), the principled rival of TPN.
enum class TdMode { Off, Sr, Sir, Fvon, Tpn, Ton, Oracle, Drift };

/// How t_d moves between images: a constant, a random walk, a drift state [t_d, ṫ_d], or TPN's prediction.
enum class TdProcess { Auto, Constant, RandomWalk, Drift, Tpn };

TdMode parse_td_mode(const std::string &s); ///< throws ovton::core::UsageError naming the valid modes
std::string to_string(TdMode m);
const std::vector<TdMode> &all_td_modes();
/// The mode strings, in the order of all_td_modes() (for option parsing and listings).
std::vector<std::string> all_td_mode_names();

TdProcess parse_td_process(const std::string &s); ///< auto | constant | random_walk | drift | tpn
std::string to_string(TdProcess p);

/// Modes that shift observations on the image plane (paper eq. 1–2).
inline bool uses_sir(TdMode m) {
  return m == TdMode::Sir || m == TdMode::Fvon || m == TdMode::Tpn || m == TdMode::Ton;
}
inline bool uses_fvon(TdMode m) {
  return m == TdMode::Fvon || m == TdMode::Ton;
}
/// Modes whose clone depends on t_d (OpenVINS' state-relevant model).
inline bool uses_state_relevant(TdMode m) {
  return m == TdMode::Sr || m == TdMode::Drift;
}
/// Modes with t_d in the filter state.
inline bool estimates_td(TdMode m) {
  return m != TdMode::Off && m != TdMode::Oracle;
}

/// The process a mode runs: `configured` unless it is Auto; then tpn/ton -> Tpn, drift -> Drift, others Constant.
/// Modes that do not estimate t_d (off, oracle) always run Constant.
TdProcess resolve_td_process(TdMode m, TdProcess configured);

/// A mode with an optional process, as `compare --modes` and `run --td-mode` accept it: "MODE" or "MODE+PROCESS"
/// (e.g. "sr+random_walk", "sir+drift"). `name` is the string itself: it names CSV files and table rows.
struct ModeSpec {
  std::string name;
  TdMode mode = TdMode::Sr;
  TdProcess process = TdProcess::Auto;
};
ModeSpec parse_mode_spec(const std::string &s); ///< throws ovton::core::UsageError

} // namespace ovton::msckf
