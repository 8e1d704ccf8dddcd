#pragma once
// Subcommands of `ovton`. Each parses its own flags (Boost.Program_options) and returns an exit code;
// library errors (ovton::core::DataError, UsageError) propagate to main(), which prints them.
#include <string>
#include <vector>

namespace ovton::cli {

using Args = std::vector<std::string>; ///< arguments after the subcommand name

int cmd_eval(const Args &args);
int cmd_info(const Args &args);
int cmd_simulate(const Args &args);
int cmd_perturb(const Args &args);
int cmd_run(const Args &args);
int cmd_compare(const Args &args);
int cmd_benchmark(const Args &args);
int cmd_diagnose(const Args &args);
int cmd_velocities(const Args &args);
int cmd_track(const Args &args);
int cmd_trackstats(const Args &args);
int cmd_export(const Args &args);
int cmd_calibrate(const Args &args);

} // namespace ovton::cli
