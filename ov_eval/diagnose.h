#pragma once
// `ovton diagnose`: which effect the filter's model lacks, read from its residual log alone.
//
// Every candidate effect predicts the logged residual r (2 rows per observation, pixels) as a linear function of
// logged columns, r ≈ X_c·β_c. The candidates are fitted by robust (Huber) weighted least squares and selected by
// forward stepwise regression: the candidate that removes the largest share of the residual's loss is tested first
// (significance of its coefficients with standard errors clustered by the time of the updates, and share of loss
// explained);
// if it passes, it joins the model and the remaining candidates are tested for what they add beyond it. Nested
// candidates (offset drift contains a constant offset) are thereby credited only with what their extra terms add.
// docs/diagnose.md gives each model, its sign convention and the thresholds. The stages live in ov_eval/diagnose/
// (tracks, residual_design, rate_design, candidates, regression, selection, report_writer); diagnose.cpp lists them.
#include "ov_core/cam/camera_calib.h"
#include "ov_core/io/residual_log_schema.h"
#include "ov_core/types/sensor_data.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ovton::eval {

/// The residual log as `ovton run --residual-log` writes it: its schema is shared with the writer
/// (ov_core/io/residual_log_schema.h), read by header name, with file:line errors.
using ovton::core::load_residual_log;
using ovton::core::ResidualLog;
using ovton::core::ResidualLogRow;

struct DiagnoseOptions {
  int image_height = 0;                  ///< rows of the image; 0: the largest v_px in the log
  double fu = 0, fv = 0, cu = 0, cv = 0; ///< intrinsics [px]; fu 0: fitted from (u_px, x_norm) in the log
  /// The dataset's camera (ovton diagnose --dataset). When set it also gives fu..cv, the image height, the distortion
  /// (focal and k1 effects are mapped through it exactly) and the camera-body rotation, with which the camera's
  /// rotation along a track is integrated from the logged body rates for the point projection (docs/diagnose.md);
  /// without it the distortion is ignored and the camera is taken as not rotating along a track.
  ovton::core::CameraCalib camera;
  bool have_camera = false;
  /// The dataset's raw IMU readings (IMU clock). With them and the camera, the time candidates are tested on the
  /// camera's angular rate seen in the images against the gyro's (docs/diagnose.md), not on the residual, where a
  /// filter's poses absorb a time offset.
  std::vector<ovton::core::ImuData> imu;
  /// The filter's calibration per update (the calibration log beside the residual log, ov_core/io/
  /// residual_log_schema.h). When given, the rates compare the images with the IMU through it: the camera-body
  /// rotation, the IMU intrinsics, the readout time and the focal the filter held at each image (docs/diagnose.md).
  std::vector<ovton::core::CalibrationLogRow> calibration;
  double gravity_mag = 9.81;   ///< |g| [m/s²] the accelerometer is compared with (the filter's gravity_mag)
  double min_sigma = 5.0;      ///< significance a candidate needs (Gaussian-equivalent σ)
  double min_explained = 0.02; ///< share of the residual loss it must remove
  double huber_k = 3.0;        ///< Huber threshold in robust σ of the residual components
  int time_bins = 12;          ///< bins of the per-time-bin δt(t) estimate
  int plot_bins = 16;          ///< quantile bins of the residual-vs-variable plots
  /// false (default): the image velocity of an observation is the three-point derivative of its track's predicted
  /// observations ẑ = z − r, which carry none of the measured pixels' noise. The logged velocity (a backward difference
  /// that includes the observation's own noise, as the filter's SIR shift uses it) correlates with the residual through
  /// that noise and fakes a time offset of about σ²/(Δt·var V): 18 ms on the clean builtin simulation
  /// (docs/diagnose.md).
  bool use_logged_velocity = false;
  double min_velocity_share = 0.5; ///< logged velocity only: below this share of rows with one, time tests are skipped
};

/// One estimated quantity of a candidate, in the unit shown to the user.
struct EffectEstimate {
  std::string name, unit;
  double value = 0, stderr_ = 0;
};

/// Binned mean of the residual (projected on the candidate's effect direction) against its explaining variable.
struct BinnedCurve {
  std::string xlabel, ylabel;
  std::vector<double> x, mean, se;
  double slope = 0, intercept = 0; ///< the fitted line in these axes
};

struct CandidateResult {
  std::string key;         ///< td_const, td_drift, rolling_shutter, focal, principal_point, radial_k1, gyro_scale
  std::string description; ///< the model in one line
  std::vector<EffectEstimate> estimates; ///< from the candidate fitted alone (plus the candidates selected before it)
  double explained_alone = 0;            ///< share of the residual loss it removes on its own
  double explained_added = 0;            ///< share it adds to the candidates selected before it
  double sigma = 0;                      ///< Gaussian-equivalent significance of its terms (Wald, cluster-robust)
  bool explained = false;                ///< verdict: selected by the stepwise procedure
  /// false: not testable on this log — it cannot show the effect at a size that matters (too few independent
  /// clusters for its terms, or the smallest size it could name is larger than a calibration is plausibly off by;
  /// the note says which). Not an effect, and not evidence of its absence.
  bool testable = true;
  int rank = 0;      ///< 1-based; selected candidates first, in selection order
  BinnedCurve curve; ///< for the plot
  std::string note;  ///< why it was skipped or what limits it
};

struct TimeBin {
  double t_s = 0;                 ///< bin centre, seconds from the first used row
  double td_ms = 0, td_se_ms = 0; ///< offset error δt in the bin (true − filter's)
  double td_filter_ms = 0;        ///< mean of the filter's t̂_d in the bin: t̂_d + δt estimates the true offset
  long observations = 0;
};

/// Structure the residual keeps after the selected candidates, binned by where it shows (unexplained.h).
struct UnexplainedStructure {
  std::string where;    ///< "time", "image region", "image speed"
  double explained = 0; ///< share of the leftover's loss the bin means remove
  double sigma = 0;     ///< Gaussian-equivalent significance of the bin means (Wald, cluster-robust)
  bool flagged = false; ///< sigma and share pass the candidates' bars: the verdict UNEXPLAINED
  bool testable = true; ///< false: more bin means than the log's independent clusters can test
  std::string largest;  ///< the bin with the largest mean, and that mean (px, u and v)
};

struct DiagnoseReport {
  std::string log_file;
  long rows_read = 0, rows_used = 0, tracks_used = 0;
  long rows_triangulation_failed = 0, rows_without_velocity = 0;
  double duration_s = 0;
  double residual_rms_px = 0, robust_sigma_px = 0;
  double fu = 0, fv = 0, cu = 0, cv = 0; ///< used (given or fitted)
  bool intrinsics_fitted = false;
  int image_height = 0;
  DiagnoseOptions options;
  std::vector<CandidateResult> candidates; ///< in rank order
  std::vector<TimeBin> td_bins;            ///< empty without velocities
  bool time_from_rates = false;            ///< time candidates fitted on vision vs gyro rates (else on the residual)
  /// What the residual keeps beyond its noise after the selected candidates, by time, image region and image speed;
  /// a flagged entry is the verdict UNEXPLAINED (an effect no candidate models).
  std::vector<UnexplainedStructure> unexplained;
  /// Non-empty: nothing is testable on this log (too few observations, e.g. a platform that did not move, so that
  /// the filter made no feature update), and why. Every candidate is then listed as not testable.
  std::string not_testable;
};

/// Runs every candidate on the log. A log with too few usable rows to say anything gets a report whose candidates are
/// all not testable (DiagnoseReport::not_testable says why), not an error: a still platform writes such a log.
DiagnoseReport diagnose(const ResidualLog &log, const DiagnoseOptions &opt = {});

/// Writes diagnose.md, diagnose.json and PNG plots (top candidates, δt per time bin) into out_dir; returns the files.
std::vector<std::string> write_diagnose_report(const DiagnoseReport &report, const std::string &out_dir);

/// The ranking as a fixed-width text table (what the CLI prints).
std::string format_ranking(const DiagnoseReport &report);

} // namespace ovton::eval
