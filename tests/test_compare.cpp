// `ovton compare`: the report (tables, plots) over real runs on a small simulated dataset, the parallel runner, mode
// list parsing, and the command itself end to end when the ovton binary is built beside this test.
#include "ov_core/io/dataset.h"
#include "ov_core/types/errors.h"
#include "ov_eval/report.h"
#include "ov_sim/simulator.h"
#include "test_util.h"
#include "tools/compare_report.h"

#include <opencv2/imgcodecs.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>
#include <sys/wait.h>

namespace fs = std::filesystem;
using namespace ovton::core;
using namespace ovton::eval;

namespace {

/// results.csv as rows of cells keyed by the header (no quoted cells in these tests).
std::vector<std::map<std::string, std::string>> read_csv(const std::string &file) {
  std::istringstream in(ovtest::read_text(file));
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  const auto split = [](const std::string &l) {
    std::vector<std::string> cells;
    std::string c;
    std::istringstream s(l);
    while (std::getline(s, c, ','))
      cells.push_back(c);
    if (!l.empty() && l.back() == ',')
      cells.push_back("");
    return cells;
  };
  while (std::getline(in, line)) {
    if (header.empty()) {
      header = split(line);
      continue;
    }
    const auto cells = split(line);
    EXPECT_EQ(cells.size(), header.size()) << line;
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < header.size() && i < cells.size(); ++i)
      row[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

double num(const std::string &cell) {
  return cell.empty() ? std::nan("") : std::stod(cell);
}

/// One small feature-level simulation (8 s of the built-in flight, drifting offset) shared by every test here.
class CompareTest : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<ovtest::TempDir>();
    ovton::sim::SimOptions o;
    o.out_dir = (*dir_) / "sim";
    o.duration_s = 8.0;
    o.seed = 7;
    o.features_only = true;
    o.td.kind = ovton::sim::TdModelKind::Drift;
    o.td.td0_s = 0.010;
    o.td.bias_s_per_s = 1e-4;
    o.td.noise_s_per_sqrt_s = 1e-4;
    ovton::sim::write_simulation(o);
    data_ = std::make_unique<Dataset>(load_dataset(o.out_dir));
  }
  static void TearDownTestSuite() {
    data_.reset();
    dir_.reset();
  }

  static std::unique_ptr<ovtest::TempDir> dir_;
  static std::unique_ptr<Dataset> data_;
};

std::unique_ptr<ovtest::TempDir> CompareTest::dir_;
std::unique_ptr<Dataset> CompareTest::data_;

} // namespace

TEST_F(CompareTest, ThreeModesGiveTableAndPlots) {
  const Dataset &data = *data_;
  ASSERT_TRUE(data.has_td_truth());
  const auto names = parse_name_list("off, sr,oracle", ovton::msckf::all_td_mode_names(), "mode");
  ASSERT_EQ(names, (std::vector<std::string>{"off", "sr", "oracle"}));

  // What `ovton compare --modes off,sr,oracle --init groundtruth` does, through the same function.
  ovton::cli::CompareRequest req;
  req.modes = ovton::cli::parse_compare_modes("off,sr,oracle");
  req.base.init.mode = ovton::msckf::InitMode::GroundTruth;
  req.out_dir = (*dir_) / "results";
  req.jobs = 2;
  req.info.command_line = "ovton compare --dataset " + data.root + " --modes off,sr,oracle --out X --init groundtruth";
  std::ostringstream log;
  req.log = &log;
  const ovton::cli::CompareResult res = ovton::cli::run_compare(data, req);
  const auto &runs = res.runs;
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(res.failed, 0);
  for (size_t i = 0; i < runs.size(); ++i) {
    EXPECT_EQ(runs[i].name, names[i]); // order of the request, whichever finished first
    EXPECT_TRUE(runs[i].ok()) << runs[i].status;
    EXPECT_GT(runs[i].traj.size(), 100u);
    EXPECT_NE(log.str().find("[" + std::to_string(i + 1) + "/3]"), std::string::npos) << log.str(); // a line each
  }
  const ReportFiles &f = res.files;

  const auto csv = read_csv(f.csv);
  ASSERT_EQ(csv.size(), 3u);
  std::map<std::string, std::map<std::string, std::string>> by_mode;
  for (const auto &r : csv)
    by_mode[r.at("mode")] = r;
  for (const auto &n : names) {
    ASSERT_TRUE(by_mode.count(n)) << n;
    const auto &r = by_mode[n];
    EXPECT_EQ(r.at("status"), "ok");
    const double ape = num(r.at("ape_rmse_m"));
    EXPECT_TRUE(std::isfinite(ape)) << n;
    EXPECT_LT(ape, 0.5) << n; // 8 s from the true initial state: a broken run would be metres off
    EXPECT_TRUE(std::isfinite(num(r.at("are_deg")))) << n;
    EXPECT_TRUE(std::isfinite(num(r.at("tpe_rmse_mm")))) << n;
    EXPECT_GT(num(r.at("runtime_s")), 0.0) << n;
    EXPECT_GT(num(r.at("realtime_factor")), 0.0) << n;
    EXPECT_GT(num(r.at("ms_per_frame")), 0.0) << n;
    EXPECT_FALSE(r.at("cit_frames").empty()) << n; // the dataset has a truth: CIT is defined (-1 = never)
  }
  // The oracle is handed the true offset, so its timing position error vanishes; `off` keeps 10 ms against a
  // drifting truth and must show it.
  EXPECT_LT(num(by_mode["oracle"].at("tpe_rmse_mm")), 0.05);
  EXPECT_GT(num(by_mode["off"].at("tpe_rmse_mm")), 1.0);
  EXPECT_NEAR(num(by_mode["oracle"].at("final_td_ms")), data.td_truth.back().td_s * 1e3, 0.1);
  EXPECT_NEAR(num(by_mode["off"].at("final_td_ms")), 0.0, 1e-9); // fixed at the (default) initial value

  for (const std::string &png : {f.td_png, f.ape_png, f.top_png}) {
    ASSERT_FALSE(png.empty());
    const cv::Mat img = cv::imread(png);
    ASSERT_FALSE(img.empty()) << png;
    EXPECT_GE(img.cols, 400);
    EXPECT_GE(img.rows, 300);
  }
  EXPECT_EQ(fs::path(f.td_png).filename(), "td.png");
  EXPECT_EQ(fs::path(f.ape_png).filename(), "ape.png");
  EXPECT_EQ(fs::path(f.top_png).filename(), "top.png");

  const std::string md = ovtest::read_text(f.md);
  EXPECT_NE(md.find(req.info.command_line), std::string::npos);
  EXPECT_NE(md.find(data.root), std::string::npos);
  EXPECT_NE(md.find("| oracle | ok |"), std::string::npos) << md;
  EXPECT_NE(md.find("![t_d estimate and truth over time](td.png)"), std::string::npos);
  EXPECT_FALSE(fs::exists(f.csv + ".tmp"));
}

TEST(CompareModes, UnknownModeIsAUsageErrorNamingIt) {
  try {
    parse_name_list("off,frobnicate,sr", ovton::msckf::all_td_mode_names(), "mode");
    FAIL() << "unknown mode accepted";
  } catch (const UsageError &e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'frobnicate'"), std::string::npos) << what;
    EXPECT_NE(what.find("oracle"), std::string::npos) << what; // the valid names are listed
  }
  EXPECT_THROW(parse_name_list("off,sr,off", ovton::msckf::all_td_mode_names(), "mode"), UsageError);
  EXPECT_THROW(parse_name_list("off,,sr", ovton::msckf::all_td_mode_names(), "mode"), UsageError);
  EXPECT_THROW(parse_name_list("", ovton::msckf::all_td_mode_names(), "mode"), UsageError);
}

TEST(CompareRunner, FailingRunIsReportedAndTheOthersContinue) {
  const std::vector<std::string> names = {"a", "b", "c", "d"};
  std::atomic<int> started{0};
  const auto runs = run_parallel(names, 3, [&](const std::string &n) {
    ++started;
    if (n == "b")
      throw DataError("b.csv", 12, "broken row");
    RunRecord r;
    r.traj.resize(n == "c" ? 2 : 1);
    return r;
  });
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(started.load(), 4);
  EXPECT_EQ(runs[0].status, "ok");
  EXPECT_EQ(runs[1].status, "failed: b.csv:12: broken row");
  EXPECT_EQ(runs[2].traj.size(), 2u);
  EXPECT_EQ(runs[3].name, "d");
  // A stop request leaves the remaining runs recorded as not run rather than missing.
  const auto stopped = run_parallel(
      names, 1, [](const std::string &) { return RunRecord{}; }, nullptr, [] { return true; });
  for (const auto &r : stopped)
    EXPECT_EQ(r.status, "not run (interrupted)");
}

TEST(CompareReport, RunsWithoutGroundTruthOrTrajectoryStillGiveATable) {
  Dataset data; // no ground truth, no offset truth
  data.root = "nowhere";
  data.kind = "euroc";
  RunRecord ok, failed;
  ok.name = "sr";
  for (int k = 0; k < 5; ++k) {
    StateSample s;
    s.t_ns = 1000000000LL + k * 50000000LL;
    s.p = Eigen::Vector3d(0.1 * k, 0.0, 0.0);
    s.has_td = true;
    s.td_s = 0.002;
    s.td_sigma_s = 0.0005;
    ok.traj.push_back(s);
  }
  failed.name = "sir";
  failed.status = "failed: no | good";
  const std::vector<RunRecord> runs = {ok, failed};
  const auto rows = evaluate_runs(runs, data);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_FALSE(rows[0].evaluated);
  EXPECT_NEAR(rows[0].final_td_ms, 2.0, 1e-12);
  ovtest::TempDir tmp;
  ReportInfo info;
  info.command_line = "ovton compare --dataset nowhere";
  const ReportFiles f = write_report(tmp.str(), runs, rows, data, info);
  EXPECT_TRUE(f.ape_png.empty()); // nothing to align against
  EXPECT_FALSE(f.td_png.empty());
  EXPECT_FALSE(f.top_png.empty()); // the raw estimate still has a shape
  const auto csv = read_csv(f.csv);
  ASSERT_EQ(csv.size(), 2u);
  EXPECT_EQ(csv[0].at("ape_rmse_m"), "");
  EXPECT_EQ(csv[1].at("status"), "failed: no | good");
  const std::string md = ovtest::read_text(f.md);
  EXPECT_NE(md.find("failed: no \\| good"), std::string::npos); // a '|' must not split the Markdown cell
  EXPECT_NE(md.find("not drawn"), std::string::npos);
}

// The command itself, through a shell, when the CLI was built beside the tests (it is, in this project's build).
TEST_F(CompareTest, CommandLineEndToEnd) {
  const fs::path ovton = fs::read_symlink("/proc/self/exe").parent_path() / "ovton";
  if (!fs::exists(ovton))
    GTEST_SKIP() << ovton << " not built";
  const std::string out = (*dir_) / "cli", err = (*dir_) / "cli_err.txt";
  // A dataset without time-offset truth: oracle is skipped with a message, the others run.
  const std::string no_truth = (*dir_) / "no_truth";
  fs::copy(data_->root, no_truth, fs::copy_options::recursive);
  fs::remove_all(fs::path(no_truth) / "mav0/td_truth");

  const std::string cmd = ovton.string() + " compare --dataset " + no_truth + " --modes off,sr,oracle --out " + out +
                          " --init groundtruth --jobs 2 >/dev/null 2>" + err;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ovtest::read_text(err);
  const std::string log = ovtest::read_text(err);
  EXPECT_NE(log.find("oracle skipped"), std::string::npos) << log;
  EXPECT_NE(log.find("compare [2/2]"), std::string::npos) << log; // one line per finished mode
  const auto csv = read_csv(out + "/results.csv");
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[2].at("mode"), "oracle");
  EXPECT_EQ(csv[2].at("status").rfind("skipped", 0), 0u);
  EXPECT_TRUE(std::isfinite(num(csv[0].at("ape_rmse_m"))));
  EXPECT_TRUE(fs::exists(out + "/traj_off.csv"));
  EXPECT_TRUE(fs::exists(out + "/traj_sr.csv"));
  EXPECT_FALSE(fs::exists(out + "/traj_oracle.csv"));
  const std::string md = ovtest::read_text(out + "/results.md");
  EXPECT_NE(md.find("ovton compare --dataset " + no_truth + " --modes off,sr,oracle --out " + out), std::string::npos)
      << md;

  // A typo in the mode list is refused before anything runs, naming the mode (exit code 2: usage).
  const std::string bad =
      ovton.string() + " compare --dataset " + no_truth + " --modes off,sri --out " + out + "_bad >/dev/null 2>" + err;
  const int rc = std::system(bad.c_str());
  ASSERT_TRUE(WIFEXITED(rc));
  EXPECT_EQ(WEXITSTATUS(rc), 2);
  EXPECT_NE(ovtest::read_text(err).find("'sri'"), std::string::npos) << ovtest::read_text(err);
  EXPECT_FALSE(fs::exists(out + "_bad"));
}
