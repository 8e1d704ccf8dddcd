#include "ov_sim/perturb.h"
#include "ov_core/io/dataset.h"
#include "ov_core/io/trajectory_io.h"
#include "ov_core/types/errors.h"
#include "ov_sim/random.h"

#include <filesystem>
#include <fstream>
#include <yaml-cpp/yaml.h>

namespace fs = std::filesystem;

namespace ovton::sim {

PerturbReport perturb_dataset(const PerturbOptions &opt) {
  if (opt.in_dir.empty() || opt.out_dir.empty())
    throw ovton::core::UsageError("perturb: need an input and an output folder");
  const fs::path in_mav0 =
      fs::exists(fs::path(opt.in_dir) / "mav0") ? fs::path(opt.in_dir) / "mav0" : fs::path(opt.in_dir);
  const fs::path out_mav0 = fs::path(opt.out_dir) / "mav0";
  if (fs::exists(out_mav0))
    throw ovton::core::UsageError("perturb: " + out_mav0.string() + " already exists; choose an empty output folder");
  if (fs::weakly_canonical(in_mav0) == fs::weakly_canonical(out_mav0))
    throw ovton::core::UsageError("perturb: output folder is the input folder");

  ovton::core::LoadOptions lo;
  lo.check_images_exist = true;
  const ovton::core::Dataset ds = ovton::core::load_dataset(opt.in_dir, lo);
  if (ds.images.empty())
    throw ovton::core::DataError((in_mav0 / "cam0" / "data.csv").string(), "no images");

  std::vector<int64_t> t_true;
  for (const auto &im : ds.images)
    t_true.push_back(im.t_cam_ns);
  TdModelOptions tdo = opt.td;
  tdo.seed = derive_seed(opt.seed, 2);
  const std::vector<TimedImage> frames = apply_td_model(t_true, tdo);

  // Everything but cam0's image list and images: csv/yaml copied, other image folders linked.
  fs::create_directories(out_mav0);
  for (auto it = fs::recursive_directory_iterator(in_mav0); it != fs::recursive_directory_iterator(); ++it) {
    const fs::path rel = fs::relative(it->path(), in_mav0);
    if (rel == fs::path("cam0") / "data" || rel == fs::path("cam0") / "data.csv" ||
        rel.begin()->string() == "td_truth") {
      if (it->is_directory())
        it.disable_recursion_pending();
      continue;
    }
    if (it->is_directory() && rel.filename() == "data") {
      fs::create_directories((out_mav0 / rel).parent_path());
      fs::create_directory_symlink(fs::absolute(it->path()), out_mav0 / rel);
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_directory()) {
      fs::create_directories(out_mav0 / rel);
      continue;
    }
    const std::string ext = it->path().extension().string();
    if (ext == ".csv" || ext == ".yaml" || ext == ".txt")
      fs::copy_file(it->path(), out_mav0 / rel);
  }

  const fs::path img_dir = out_mav0 / "cam0" / "data";
  fs::create_directories(img_dir);
  std::ofstream list(out_mav0 / "cam0" / "data.csv");
  if (!list)
    throw ovton::core::DataError((out_mav0 / "cam0" / "data.csv").string(), "cannot open for writing");
  list << "#timestamp [ns],filename\n";
  std::vector<ovton::core::TdSample> td;
  for (size_t k = 0; k < frames.size(); ++k) {
    const fs::path src = fs::absolute(ds.images[k].path);
    const std::string name = std::to_string(frames[k].t_cam_ns) + src.extension().string();
    fs::create_symlink(src, img_dir / name); // linked, not copied: a full EuRoC sequence is ~1 GB of PNG
    list << frames[k].t_cam_ns << "," << name << "\n";
    td.push_back(ovton::core::TdSample{frames[k].t_cam_ns, frames[k].td_s()});
  }
  list.close();
  fs::create_directories(out_mav0 / "td_truth");
  ovton::core::write_td_truth((out_mav0 / "td_truth" / "data.csv").string(), td);

  YAML::Emitter e;
  e.SetDoublePrecision(15);
  e << YAML::BeginMap << YAML::Key << "generator" << YAML::Value << "ovton perturb";
  e << YAML::Key << "source" << YAML::Value << fs::absolute(in_mav0).string();
  e << YAML::Key << "seed" << YAML::Value << opt.seed;
  e << YAML::Key << "convention" << YAML::Value << "t_imu = t_cam + td; original stamps taken as t_imu";
  e << YAML::Key << "model" << YAML::Value << to_string(opt.td.kind);
  e << YAML::Key << "td0_s" << YAML::Value << opt.td.td0_s;
  e << YAML::Key << "bias_s_per_s" << YAML::Value << opt.td.bias_s_per_s;
  e << YAML::Key << "noise_s_per_sqrt_s" << YAML::Value << opt.td.noise_s_per_sqrt_s;
  e << YAML::EndMap;
  std::ofstream y(fs::path(opt.out_dir) / "perturb.yaml");
  y << e.c_str() << "\n";

  PerturbReport rep;
  rep.n_images = frames.size();
  rep.td_first_s = frames.front().td_s();
  rep.td_last_s = frames.back().td_s();
  return rep;
}

} // namespace ovton::sim
