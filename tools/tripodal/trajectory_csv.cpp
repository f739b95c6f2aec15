// trajectory.csv of `tripodal run`, and the text helpers the writers share.
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "run_outputs.hpp"

namespace tripodal::app {

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream f(file, std::ios::binary | std::ios::trunc);
  if (!f || !f.write(text.data(), static_cast<std::streamsize>(text.size()))) throw std::runtime_error("cannot write " + file.string());
}

std::string trajectory_csv(const std::vector<TrajectorySample>& traj) {
  std::string out = "t_s,x_m,y_m,theta_rad,estimate_x_m,estimate_y_m,estimate_theta_rad,localized,cleaning\n";
  char buf[256];
  for (const TrajectorySample& s : traj) {
    std::snprintf(buf, sizeof buf, "%.3f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%d\n", to_seconds(s.t), s.truth.x_m, s.truth.y_m,
                  s.truth.theta_rad, s.estimate.x_m, s.estimate.y_m, s.estimate.theta_rad, s.localized ? 1 : 0, s.cleaning ? 1 : 0);
    out += buf;
  }
  return out;
}

}  // namespace tripodal::app
