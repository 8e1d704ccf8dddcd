#include "ov_core/io/run_mcap_writer.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/image_codecs.h"
#include "ov_core/io/ros2_messages.h"
#include "ov_core/io/ros2_schemas.h"
#include "ov_core/types/errors.h"
#include "ov_core/types/state_interpolation.h"

#include <map>

namespace ovton::core {

namespace {

const char *const kWorld = "world";

struct Color {
  double r, g, b, a;
};
// Green for features an update used, red for those its gate refused, blue for the rest.
constexpr Color kUsed{0.1, 0.9, 0.2, 1.0}, kGated{1.0, 0.15, 0.1, 1.0}, kTracked{0.2, 0.55, 1.0, 1.0};
constexpr Color kWhite{1, 1, 1, 1}, kShade{0, 0, 0, 0.6};

void write_color(CdrWriter &w, const Color &c) {
  const double v[4] = {c.r, c.g, c.b, c.a};
  w.f64_array(v, 4);
}

void write_pose_stamped(CdrWriter &w, int64_t t_ns, const Eigen::Vector3d &p, const Eigen::Quaterniond &q) {
  write_ros2_header(w, t_ns, kWorld);
  write_ros2_pose(w, p, q);
}

std::vector<uint8_t> float64_message(double v) {
  CdrWriter w;
  w.f64(v);
  return w.take();
}

uint64_t log_time(int64_t t_ns) {
  if (t_ns < 0)
    throw UsageError("RunMcapWriter: stamp " + std::to_string(t_ns) + " ns is negative (MCAP times are unsigned)");
  return static_cast<uint64_t>(t_ns);
}

struct Pose {
  int64_t t_ns;
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
};

std::vector<uint8_t> path_message(const std::vector<Pose> &poses, int64_t stamp_ns) {
  CdrWriter w;
  write_ros2_header(w, stamp_ns, kWorld);
  w.seq_length(poses.size());
  for (const Pose &p : poses)
    write_pose_stamped(w, p.t_ns, p.p, p.q);
  return w.take();
}

std::vector<uint8_t> annotations_message(int64_t t_cam_ns, const std::vector<RunFeature> &features) {
  CdrWriter w;
  w.seq_length(0); // circles
  const std::pair<FeatureStatus, Color> groups[] = {
      {FeatureStatus::Tracked, kTracked}, {FeatureStatus::Gated, kGated}, {FeatureStatus::Used, kUsed}};
  size_t counts[3] = {0, 0, 0};
  w.seq_length(3); // points: one annotation per status, drawn in this order (used on top)
  for (size_t g = 0; g < 3; ++g) {
    std::vector<const RunFeature *> of;
    for (const RunFeature &f : features)
      if (f.status == groups[g].first)
        of.push_back(&f);
    counts[g] = of.size();
    write_ros2_time(w, t_cam_ns);
    w.u8(1); // POINTS
    w.seq_length(of.size());
    for (const RunFeature *f : of)
      w.f64_array(f->uv.data(), 2);
    write_color(w, groups[g].second);
    w.seq_length(0); // outline_colors
    write_color(w, groups[g].second);
    w.f64(5.0); // thickness: the point's size in pixels
  }
  w.seq_length(1); // texts
  write_ros2_time(w, t_cam_ns);
  const double at[2] = {8.0, 20.0};
  w.f64_array(at, 2);
  w.string("used " + std::to_string(counts[2]) + "  gated " + std::to_string(counts[1]) + "  tracked " +
           std::to_string(counts[0]));
  w.f64(16.0);
  write_color(w, kWhite);
  write_color(w, kShade);
  return w.take();
}

} // namespace

struct RunMcapWriter::Impl {
  Impl(const std::string &path, const RunMcapOptions &o) : opt(o), w(path, o.mcap) {}

  uint16_t channel(const std::string &topic, const std::string &type) {
    const uint16_t schema = w.add_schema(type, "ros2msg", ros2_schema(type));
    const uint16_t id = w.add_channel(topic, schema, "cdr", {{"offered_qos_profiles", ""}});
    topics[id] = topic;
    return id;
  }

  /// The ground truth from the first state on, once at that state's time: Foxglove shows it from the first frame, and
  /// a file whose run was killed has it.
  void write_truth_path(int64_t first_ns) {
    std::vector<Pose> truth;
    for (const StateSample &g : gt)
      if (g.t_ns >= first_ns)
        truth.push_back({g.t_ns, g.p, g.has_orientation ? g.q_WB.normalized() : Eigen::Quaterniond::Identity()});
    if (!truth.empty())
      w.write(path_truth, log_time(first_ns), path_message(truth, first_ns));
  }

  RunMcapOptions opt;
  McapWriter w;
  std::map<uint16_t, std::string> topics;
  uint16_t image = 0, features = 0, pose = 0, pose_truth = 0, tf = 0, tf_static = 0, path = 0, path_truth = 0;
  uint16_t td = 0, td_lower = 0, td_upper = 0, td_truth = 0;
  std::vector<StateSample> gt;
  std::vector<TdSample> td_gt;
  std::vector<Pose> poses;
  int64_t last_path_ns = 0;
  size_t poses_in_last_path = 0;
  bool closed = false;
};

RunMcapWriter::RunMcapWriter(const std::string &path, const RunMcapOptions &opt) {
  if (opt.image_format != "jpeg" && opt.image_format != "raw")
    throw UsageError("RunMcapWriter: image format '" + opt.image_format + "' (expected jpeg or raw)");
  if (!(opt.path_period_s > 0))
    throw UsageError("RunMcapWriter: path_period_s must be positive");
  impl_ = std::make_unique<Impl>(path, opt);
  Impl &m = *impl_;
  m.image = m.channel("/ovton/image",
                      opt.image_format == "jpeg" ? "sensor_msgs/msg/CompressedImage" : "sensor_msgs/msg/Image");
  m.features = m.channel("/ovton/features", "foxglove_msgs/msg/ImageAnnotations");
  m.pose = m.channel("/ovton/pose", "geometry_msgs/msg/PoseStamped");
  m.pose_truth = m.channel("/ovton/pose_truth", "geometry_msgs/msg/PoseStamped");
  m.tf = m.channel("/tf", "tf2_msgs/msg/TFMessage");
  m.tf_static = m.channel("/tf_static", "tf2_msgs/msg/TFMessage");
  m.path = m.channel("/ovton/path", "nav_msgs/msg/Path");
  m.path_truth = m.channel("/ovton/path_truth", "nav_msgs/msg/Path");
  m.td = m.channel("/ovton/td_ms", "std_msgs/msg/Float64");
  m.td_lower = m.channel("/ovton/td_lower_ms", "std_msgs/msg/Float64");
  m.td_upper = m.channel("/ovton/td_upper_ms", "std_msgs/msg/Float64");
  m.td_truth = m.channel("/ovton/td_truth_ms", "std_msgs/msg/Float64");
}

RunMcapWriter::~RunMcapWriter() {
  try {
    close();
  } catch (...) { // NOLINT(bugprone-empty-catch): a destructor must not throw; close() reports when called itself
  }
}

void RunMcapWriter::set_truth(std::vector<StateSample> groundtruth, std::vector<TdSample> td_truth) {
  impl_->gt = std::move(groundtruth);
  impl_->td_gt = std::move(td_truth);
}

std::vector<uint8_t> RunMcapWriter::encode_image(int64_t t_cam_ns, const cv::Mat &gray) const {
  if (impl_->opt.image_format != "jpeg")
    return encode_ros2_image(gray, t_cam_ns, "cam");
  std::vector<uchar> bytes;
  if (!core::encode_image(".jpg", gray, bytes, {jpeg_quality_param(), impl_->opt.jpeg_quality}))
    throw UsageError("RunMcapWriter: the image at " + std::to_string(t_cam_ns) + " ns cannot be encoded as JPEG");
  return encode_ros2_compressed_image(bytes, "jpeg", t_cam_ns, "cam");
}

void RunMcapWriter::add_image(int64_t t_cam_ns, int64_t t_imu_ns, const cv::Mat &gray,
                              const std::vector<RunFeature> &features) {
  // A feature-level recording has no pixels: its features alone.
  add_encoded_image(t_cam_ns, t_imu_ns, gray.empty() ? std::vector<uint8_t>() : encode_image(t_cam_ns, gray), features);
}

void RunMcapWriter::add_encoded_image(int64_t t_cam_ns, int64_t t_imu_ns, const std::vector<uint8_t> &image_message,
                                      const std::vector<RunFeature> &features) {
  Impl &m = *impl_;
  const uint64_t t = log_time(t_imu_ns);
  if (!image_message.empty())
    m.w.write(m.image, t, image_message);
  m.w.write(m.features, t, annotations_message(t_cam_ns, features));
  if (!m.td_gt.empty())
    m.w.write(m.td_truth, t, float64_message(interpolate_td(m.td_gt, t_cam_ns) * 1e3));
}

void RunMcapWriter::add_state(const StateSample &s) {
  Impl &m = *impl_;
  const uint64_t t = log_time(s.t_ns);
  if (m.poses.empty() && m.opt.T_BC) {
    Ros2Transform c;
    c.stamp_ns = s.t_ns;
    c.parent = "imu";
    c.child = "cam";
    c.T_parent_child = *m.opt.T_BC;
    m.w.write(m.tf_static, t, encode_ros2_tf({c}));
  }
  const Eigen::Quaterniond q = s.q_WB.normalized();
  CdrWriter pose;
  write_pose_stamped(pose, s.t_ns, s.p, q);
  m.w.write(m.pose, t, pose.take());
  std::vector<Ros2Transform> tf(1);
  tf[0].stamp_ns = s.t_ns;
  tf[0].parent = kWorld;
  tf[0].child = "imu";
  tf[0].T_parent_child.topLeftCorner<3, 3>() = q.toRotationMatrix();
  tf[0].T_parent_child.topRightCorner<3, 1>() = s.p;
  StateSample truth;
  if (interpolate_state(m.gt, s.t_ns, truth) && truth.has_orientation) {
    CdrWriter tp;
    write_pose_stamped(tp, s.t_ns, truth.p, truth.q_WB.normalized());
    m.w.write(m.pose_truth, t, tp.take());
    tf.push_back(tf[0]);
    tf[1].child = "imu_truth";
    tf[1].T_parent_child.topLeftCorner<3, 3>() = truth.q_WB.normalized().toRotationMatrix();
    tf[1].T_parent_child.topRightCorner<3, 1>() = truth.p;
  }
  m.w.write(m.tf, t, encode_ros2_tf(tf));
  if (s.has_td) {
    m.w.write(m.td, t, float64_message(s.td_s * 1e3));
    m.w.write(m.td_lower, t, float64_message((s.td_s - s.td_sigma_s) * 1e3));
    m.w.write(m.td_upper, t, float64_message((s.td_s + s.td_sigma_s) * 1e3));
  }
  m.poses.push_back({s.t_ns, s.p, q});
  if (m.poses.size() == 1)
    m.write_truth_path(s.t_ns);
  if (m.poses.size() == 1 || ns_to_s(s.t_ns - m.last_path_ns) >= m.opt.path_period_s) {
    m.w.write(m.path, t, path_message(m.poses, s.t_ns));
    m.last_path_ns = s.t_ns;
    m.poses_in_last_path = m.poses.size();
  }
}

void RunMcapWriter::close() {
  if (!impl_ || impl_->closed)
    return;
  Impl &m = *impl_;
  m.closed = true;
  if (!m.poses.empty() && m.poses_in_last_path != m.poses.size())
    m.w.write(m.path, log_time(m.poses.back().t_ns), path_message(m.poses, m.poses.back().t_ns));
  m.w.close();
}

std::vector<std::pair<std::string, uint64_t>> RunMcapWriter::message_counts() const {
  std::vector<std::pair<std::string, uint64_t>> out;
  for (const auto &[id, n] : impl_->w.message_counts())
    out.emplace_back(impl_->topics.at(id), n);
  return out;
}

} // namespace ovton::core
