// Input that is readable but cannot be a real recording, checked time arithmetic, and YAML traps: each case is
// rejected with the file (and line) named, never passed on to become a silent wrong answer (issue 12).
#include "io_test_util.h"
#include "ov_core/io/csv.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_io.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/io/yaml_file.h"
#include "ov_core/types/time.h"
#include "ov_msckf_ton/core/vio_options.h"
#include "test_util.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

using namespace ovton::core;
using ovtest::expect_data_error;
using ovtest::kCamYaml;
using ovtest::kImuYaml;
using ovtest::make_euroc;
using ovtest::replace_line;
using ovtest::TempDir;
using ovtest::write_text;

namespace {

/// A copy of `yaml` with the line starting with `key` replaced by `line` (appended when absent).
std::string with_line(std::string yaml, const std::string &key, const std::string &line) {
  const auto pos = yaml.find("\n" + key);
  if (pos == std::string::npos)
    return yaml + line + "\n";
  const auto end = yaml.find('\n', pos + 1);
  return yaml.replace(pos + 1, end - pos - 1, line);
}

/// Rewrites every stamp of a list (first column) with f(stamp).
template <typename F> void map_stamps(const std::string &file, F f) {
  std::istringstream in(ovtest::read_text(file));
  std::ostringstream out;
  std::string l;
  while (std::getline(in, l)) {
    if (l.empty() || l[0] == '#') {
      out << l << "\n";
      continue;
    }
    const auto comma = l.find(',');
    out << f(std::stoll(l.substr(0, comma))) << l.substr(comma) << "\n";
  }
  write_text(file, out.str());
}

} // namespace

TEST(CheckedTime, ConversionsAndSumsReportInsteadOfOverflowing) {
  EXPECT_EQ(s_to_ns(1.5), 1500000000LL);
  EXPECT_EQ(s_to_ns(-0.0000000015), -2);
  EXPECT_THROW(s_to_ns(std::numeric_limits<double>::infinity()), UsageError);
  EXPECT_THROW(s_to_ns(std::nan("")), UsageError);
  EXPECT_THROW(s_to_ns(9.3e9), UsageError); // beyond INT64_MAX ns
  EXPECT_FALSE(try_s_to_ns(-1e300).has_value());
  EXPECT_EQ(add_ns(5, -7), -2);
  EXPECT_THROW(add_ns(std::numeric_limits<int64_t>::max(), 1), UsageError);
  EXPECT_THROW(sub_ns(std::numeric_limits<int64_t>::min(), 1), UsageError);
  EXPECT_EQ(*try_seconds_parts_to_ns(1403715274, 302142000, false), 1403715274302142000LL);
  EXPECT_EQ(*try_seconds_parts_to_ns(0, 500000000, true), -500000000LL);
  EXPECT_FALSE(try_seconds_parts_to_ns(9300000000LL, 0, false).has_value());
}

TEST(CheckedTime, TumStampsBeyondTheClockNameTheLine) {
  TempDir tmp;
  // Plain seconds past 9.2e9 overflowed sec * 1e9 (signed overflow); exponent forms reached a cast of a huge double.
  for (const char *stamp : {"9300000000.5", "1e300", "-9300000000", "inf"}) {
    write_text(tmp / "t.txt", std::string("0.5 0 0 0 0 0 0 1\n") + stamp + " 0 0 0 0 0 0 1\n");
    expect_data_error([&] { read_trajectory(tmp / "t.txt"); }, "t.txt", 2, stamp);
  }
  // Negative stamps keep their sign through the writer and back.
  StateSample s;
  s.t_ns = -1500000000LL;
  {
    TrajectoryWriter w(tmp / "neg.txt", TrajectoryFormat::Tum);
    w.write(s);
  }
  EXPECT_EQ(read_trajectory(tmp / "neg.txt").front().t_ns, -1500000000LL) << ovtest::read_text(tmp / "neg.txt");
}

TEST(ReaderPlausibility, ByteOrderMarkIsAccepted) {
  TempDir tmp;
  const std::string root = make_euroc(tmp);
  for (const char *f : {"/mav0/cam0/data.csv", "/mav0/imu0/data.csv", "/mav0/state_groundtruth_estimate0/data.csv",
                        "/mav0/cam0/sensor.yaml", "/mav0/imu0/sensor.yaml"})
    write_text(root + f, std::string(kUtf8Bom) + ovtest::read_text(root + f));
  const Dataset d = load_dataset(root);
  EXPECT_EQ(d.images.size(), 5u);
  EXPECT_EQ(d.imu.size(), 201u);
  EXPECT_EQ(d.groundtruth.size(), 21u);
  write_text(tmp / "t.txt", std::string(kUtf8Bom) + "# timestamp(s) tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n");
  EXPECT_EQ(read_trajectory(tmp / "t.txt").size(), 1u);
}

TEST(ReaderPlausibility, ImpossibleImuValuesNameFileAndLine) {
  // 1e308 after initialisation ran through the filter as NaN rows with exit 0; 500 rad/s is no real gyro either.
  for (const char *row : {"1015000000,0.01,0.02,0.03,1e308,0.2,9.81", "1015000000,500,0.02,0.03,0.1,0.2,9.81"}) {
    TempDir tmp;
    const std::string root = make_euroc(tmp);
    replace_line(root + "/mav0/imu0/data.csv", 5, row);
    expect_data_error([&] { load_dataset(root); }, "imu0/data.csv", 5, row);
  }
}

TEST(ReaderPlausibility, ImpossibleOffsetsAndFeaturePositionsNameFileAndLine) {
  TempDir tmp;
  const std::string root = make_euroc(tmp);
  write_text(root + "/mav0/td_truth/data.csv", "#timestamp_ns,td_s\n1050000000,0.01\n1100000000,1e300\n");
  expect_data_error([&] { load_dataset(root); }, "td_truth/data.csv", 3, "offset of 1e300 s");
  std::filesystem::remove_all(root + "/mav0/td_truth");
  write_text(root + "/mav0/cam0/features.csv", "1050000000,1,100,200\n1050000000,2,1e6,200\n");
  expect_data_error([&] { load_dataset(root); }, "cam0/features.csv", 2, "feature far outside the image");
}

TEST(ReaderPlausibility, StampsThatCannotBeNanosecondsNameFileAndLine) {
  {
    TempDir tmp; // images stamped in ms: 50 "ns" apart at a stated 20 Hz
    const std::string root = make_euroc(tmp);
    map_stamps(root + "/mav0/cam0/data.csv", [](int64_t t) { return t / 1000000; });
    expect_data_error([&] { load_dataset(root); }, "cam0/data.csv", 3, "image stamps in ms");
  }
  {
    TempDir tmp; // IMU in us
    const std::string root = make_euroc(tmp);
    map_stamps(root + "/mav0/imu0/data.csv", [](int64_t t) { return t / 1000; });
    expect_data_error([&] { load_dataset(root); }, "imu0/data.csv", 3, "IMU stamps in us");
  }
  {
    TempDir tmp;
    const std::string root = make_euroc(tmp);
    replace_line(root + "/mav0/cam0/data.csv", 2, "-1050000000,1050000000.png");
    expect_data_error([&] { load_dataset(root); }, "cam0/data.csv", 2, "negative stamp");
  }
  {
    TempDir tmp; // a stamp at the end of the int64 clock leaves no room for t_d
    const std::string root = make_euroc(tmp);
    replace_line(root + "/mav0/cam0/data.csv", 6, "9223372036854775807,1250000000.png");
    expect_data_error([&] { load_dataset(root); }, "cam0/data.csv", 6, "stamp at INT64_MAX");
  }
  {
    TempDir tmp; // images 1000 s after the IMU log: the replay would skip every one and write nothing
    const std::string root = make_euroc(tmp);
    map_stamps(root + "/mav0/cam0/data.csv", [](int64_t t) { return t + 1000000000000LL; });
    expect_data_error([&] { load_dataset(root); }, "cam0/data.csv", 0, "images outside the IMU log");
  }
}

// A T_BS whose last row is not [0 0 0 1] (here the translation written into the last row as well, as a transposed
// matrix has it) is not a rigid transform: refused naming the file and the matrix's line, and saying what it is.
TEST(ReaderPlausibility, TransformWhoseLastRowIsNotRigidIsRefused) {
  TempDir tmp;
  const std::string root = make_euroc(tmp);
  std::string cam = kCamYaml;
  const std::string row = "0.0, 0.0, 0.0, 1.0]";
  cam.replace(cam.find(row), row.size(), "-0.0216401454975, -0.064676986768, 0.00981073058949, 1.0]");
  write_text(root + "/mav0/cam0/sensor.yaml", cam);
  expect_data_error([&] { load_dataset(root); }, "cam0/sensor.yaml", 4, "last row of T_BS not [0 0 0 1]");
  try {
    load_dataset(root);
  } catch (const ovton::core::DataError &e) {
    EXPECT_NE(std::string(e.what()).find("'T_BS' last row is [-0.021640 -0.064677 0.009811 1.000000], not [0 0 0 1]"),
              std::string::npos)
        << e.what();
  }
}

// An IMU log at 200 Hz whose sensor.yaml says 100 (within the factor of 3 refused as a unit error): read, with a
// warning naming the log, the rates and the yaml; the matching rate warns nothing.
TEST(ReaderPlausibility, ImuRateOtherThanTheYamlsIsAWarning) {
  TempDir tmp;
  const std::string root = make_euroc(tmp);
  EXPECT_TRUE(load_dataset(root).warnings.empty());
  write_text(root + "/mav0/imu0/sensor.yaml", with_line(kImuYaml, "rate_hz", "rate_hz: 100"));
  const auto d = load_dataset(root);
  ASSERT_EQ(d.warnings.size(), 1u);
  const std::string &w = d.warnings.front();
  EXPECT_NE(w.find("imu0/data.csv: the IMU readings are 5 ms apart (median: 200 Hz) but "), std::string::npos) << w;
  EXPECT_NE(w.find("imu0/sensor.yaml's rate_hz says 100 Hz"), std::string::npos) << w;
}

TEST(ReaderPlausibility, SensorYamlValuesOutsideAnySensorNameFileAndLine) {
  struct Case {
    const char *file, *key, *line;
    long line_no;
  };
  // Line numbers: kImuYaml has rate_hz on line 3, the densities on 4-7; kCamYaml rate_hz on 10.
  const Case cases[] = {
      {"imu0/sensor.yaml", "gyroscope_noise_density", "gyroscope_noise_density: 0", 4},
      {"imu0/sensor.yaml", "accelerometer_noise_density", "accelerometer_noise_density: -2.0e-3", 6},
      {"imu0/sensor.yaml", "gyroscope_random_walk", "gyroscope_random_walk: -1", 5},
      {"imu0/sensor.yaml", "rate_hz", "rate_hz: 1e-300", 3},
      {"cam0/sensor.yaml", "rate_hz", "rate_hz: 0", 10},
  };
  for (const Case &c : cases) {
    TempDir tmp;
    const std::string root = make_euroc(tmp);
    const std::string base = std::string(c.file).rfind("imu", 0) == 0 ? kImuYaml : kCamYaml;
    write_text(root + "/mav0/" + c.file, with_line(base, c.key, c.line));
    expect_data_error([&] { load_dataset(root); }, c.file, c.line_no, c.line);
  }
}

TEST(ReaderPlausibility, YamlTrapsNameFileAndLine) {
  TempDir tmp;
  // A key set twice in a sensor.yaml: yaml-cpp keeps both and lookups see only the first, so the second value was
  // silently ignored. (The estimator config's own duplicate, unknown and mistyped keys: VioOptions in test_vio.cpp.)
  const std::string cam = kCamYaml;
  write_text(tmp / "dupnested.yaml", cam + "T_BS:\n  rows: 4\n");
  expect_data_error([&] { load_euroc_camera_yaml(tmp / "dupnested.yaml"); }, "dupnested.yaml",
                    std::count(cam.begin(), cam.end(), '\n') + 1, "duplicate T_BS");
  // An estimator config `text` is refused, naming the file and `line` (0: the file only).
  const auto bad_config = [&](const std::string &name, const std::string &text, long line, const std::string &why) {
    write_text(tmp / name, text);
    expect_data_error([&] { ovton::msckf::load_vio_options(tmp / name); }, name, line, why);
  };
  // Keys that are not names escaped as bare yaml-cpp errors (exit 1, no file).
  bad_config("key.yaml", "? [a, b]\n: 3\n", 1, "list as section");
  bad_config("key2.yaml", "update:\n  ? [a, b]\n  : 3\n", 2, "list as key");
  // Settings no run can use (checked after loading: the file is named, not the line).
  bad_config("w.yaml", "init:\n  window_s: -1\n", 0, "negative init window");
  bad_config("g.yaml", "imu:\n  gravity_mag: 1000\n", 0, "gravity of 1000 m/s^2");
  bad_config("r.yaml", "time_offset:\n  search_range_s: 5\n", 0, "search range of 5 s");
  // A Kalibr chain whose cam0 is a scalar was subscripted (yaml-cpp exception, exit 1).
  const std::string sample = std::string(OVTON_SOURCE_DIR) + "/datasets/scube_sample";
  const std::string copy = tmp / "scube";
  std::filesystem::copy(sample, copy, std::filesystem::copy_options::recursive);
  write_text(copy + "/camchain-imucam.yaml", "cam0: 5\n");
  expect_data_error([&] { load_dataset(copy); }, "camchain-imucam.yaml", 1, "scalar cam0");
  // A BOM in a config is fine.
  write_text(tmp / "bom.yaml", std::string(kUtf8Bom) + "update:\n  max_clones: 12\n");
  EXPECT_EQ(ovton::msckf::load_vio_options(tmp / "bom.yaml").update.max_clones, 12);
}

TEST(ReaderPlausibility, OutputPathsAndImagesNameTheFile) {
  TempDir tmp;
  expect_data_error([&] { require_writable(tmp / "no_such_folder/traj.csv"); }, "no_such_folder", 0, "missing folder");
  expect_data_error([&] { require_writable(tmp.str()); }, tmp.str(), 0, "a folder as output");
  EXPECT_NO_THROW(require_writable(tmp / "traj.csv"));
  EXPECT_FALSE(std::filesystem::exists(tmp / "traj.csv")); // checking creates nothing
  // An image of another size than the calibration's (it was a tracker usage error without the file's name).
  const ImageEntry e{1, tmp / "small.png", {}, 0, {}};
  expect_data_error([&] { check_gray_image(cv::Mat(10, 20, CV_8UC1), e, 752, 480); }, "small.png", 0, "wrong size");
  expect_data_error([&] { load_gray_image(e, 752, 480); }, "small.png", 0, "missing image");
}
