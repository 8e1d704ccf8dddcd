// Which cameras of a rig a run uses (`--cameras`, the `max_cameras` option): the recording keeps every camera it has,
// the run picks.
#include "ov_core/io/dataset.h"
#include "ov_core/types/errors.h"

#include <algorithm>
#include <sstream>

namespace ovton::core {

void select_cameras(Dataset &d, const std::vector<int> &cameras) {
  if (cameras.empty())
    throw UsageError("no camera selected");
  // A camera on a clock of its own has its own true offset: it goes where the camera goes, and the primary's is the
  // rig's (Dataset::td_truth). Without one, every camera has the rig's.
  const bool own_clocks =
      std::any_of(d.more_cameras.begin(), d.more_cameras.end(), [](const auto &c) { return !c.td_truth.empty(); });
  std::vector<CameraStream> all;
  all.push_back({d.cam, std::move(d.images), own_clocks ? d.td_truth : std::vector<TdSample>{}});
  for (auto &c : d.more_cameras) {
    if (own_clocks && c.td_truth.empty())
      c.td_truth = d.td_truth;
    all.push_back(std::move(c));
  }
  std::vector<bool> used(all.size(), false);
  for (const int k : cameras) {
    if (k < 0 || static_cast<size_t>(k) >= all.size())
      throw UsageError("camera " + std::to_string(k) + " is not in " + d.root + " (it has " +
                       std::to_string(all.size()) + ")");
    if (used[static_cast<size_t>(k)])
      throw UsageError("camera " + std::to_string(k) + " selected twice");
    used[static_cast<size_t>(k)] = true;
  }
  d.cam = all[static_cast<size_t>(cameras.front())].cam;
  d.images = std::move(all[static_cast<size_t>(cameras.front())].images);
  if (own_clocks)
    d.td_truth = all[static_cast<size_t>(cameras.front())].td_truth;
  d.more_cameras.clear();
  for (size_t i = 1; i < cameras.size(); ++i)
    d.more_cameras.push_back(std::move(all[static_cast<size_t>(cameras[i])]));
}

std::vector<int> parse_camera_list(const std::string &s) {
  std::vector<int> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const bool digits =
        !item.empty() && std::all_of(item.begin(), item.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!digits || item.size() > 3)
      throw UsageError("--cameras: '" + s + "' is not a comma-separated list of camera numbers (e.g. 0,1)");
    out.push_back(std::stoi(item));
  }
  if (out.empty())
    throw UsageError("--cameras: no camera given");
  return out;
}

} // namespace ovton::core
