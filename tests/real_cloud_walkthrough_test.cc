// The README's "Register your own cloud" walk-through, run as a user runs it: the ifab binary on a
// real Velodyne VLP-16 scan (data/examples/vlp16_wall, MRPT's sample, BSD-3-Clause), checked
// against an independent least-squares fit of the wall's points and for an honest status.
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ifab/perception/ply.h"

namespace ifab {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kExample = std::string(IFAB_DATA_DIR) + "/examples/vlp16_wall";
// The walk-through's crop: the wall segment and up to a metre around it (ground and bushes at
// its foot stay in, as a user's crop would leave them).
const Eigen::Vector3d kCropMin(10.0, -3.0, -1.5), kCropMax(12.5, 14.0, 0.5);
const std::string kCrop = "box 10 -3 -1.5 12.5 14 0.5";

struct CliRun {
  int exit_code{-1};
  json result;
};

CliRun RunRegister(const std::string& name, const std::string& extra) {
  const fs::path out = fs::temp_directory_path() / ("ifab_walkthrough_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(out);
  const std::string cmd = std::string(IFAB_BIN) + " register " + kExample + "/scan.ply --frame sensor --site " +
                          kExample + "/site.yaml --crop '" + kCrop + "' --out " + out.string() + " " + extra +
                          " > " + (out.string() + ".log") + " 2>&1";
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(out / "registration.json");
  if (in) r.result = json::parse(in);
  return r;
}

// Least-squares plane of the cropped points, trimmed at 3x its own rms until the set settles: a
// reference that shares nothing with ifab's gate or noise model.
struct Plane {
  Eigen::Vector3d n;
  double offset;  // n . p = offset
  int count;
};

Plane ReferencePlane() {
  const PointCloud cloud = ReadPly(kExample + "/scan.ply");
  std::vector<Eigen::Vector3d> crop;
  for (const auto& p : cloud.points)
    if ((p.array() > kCropMin.array()).all() && (p.array() < kCropMax.array()).all()) crop.push_back(p);
  std::vector<Eigen::Vector3d> set = crop;
  Plane pl{};
  for (int it = 0; it < 20; ++it) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const auto& p : set) c += p;
    c /= static_cast<double>(set.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : set) cov += (p - c) * (p - c).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    pl.n = es.eigenvectors().col(0);
    if (pl.n.x() > 0) pl.n = -pl.n;  // facing the laser, as the site's guess
    pl.offset = pl.n.dot(c);
    double ss = 0;
    for (const auto& p : set) ss += std::pow(pl.n.dot(p) - pl.offset, 2);
    const double gate = 3.0 * std::sqrt(ss / static_cast<double>(set.size()));
    std::vector<Eigen::Vector3d> next;
    for (const auto& p : crop)
      if (std::abs(pl.n.dot(p) - pl.offset) < gate) next.push_back(p);
    if (next.size() == set.size()) break;
    set = std::move(next);
  }
  pl.count = static_cast<int>(set.size());
  return pl;
}

void ExpectPlaneMatchesReference(const json& plane, const Plane& ref) {
  const Eigen::Vector3d n(plane["normal"][0].get<double>(), plane["normal"][1].get<double>(),
                          plane["normal"][2].get<double>());
  const double angle_deg = std::acos(std::min(1.0, std::abs(n.normalized().dot(ref.n)))) * 180.0 / M_PI;
  const double sign = n.dot(ref.n) < 0 ? -1.0 : 1.0;
  const double offset_mm = 1e3 * std::abs(sign * plane["offset"].get<double>() - ref.offset);
  EXPECT_LT(angle_deg, 1.0) << "normal " << n.transpose() << " vs the least-squares " << ref.n.transpose();
  EXPECT_LT(offset_mm, 3.0) << "offset " << plane["offset"] << " vs the least-squares " << ref.offset;
}

TEST(RealCloudWalkthrough, TheReferenceFitSeesAWall) {
  const Plane ref = ReferencePlane();
  EXPECT_GT(ref.count, 500);
  EXPECT_GT(std::abs(ref.n.x()), 0.99);  // a wall ahead along +x, near-vertical
  EXPECT_NEAR(ref.offset, -11.6, 0.2);
}

// Step 3: the wall alone. Its plane is recovered; the pose along it is not, and ifab says so.
TEST(RealCloudWalkthrough, AWallAloneGivesItsPlaneAndReportsThreeFreeDirections) {
  const CliRun r = RunRegister("free", "");
  ASSERT_FALSE(r.result.is_null()) << "no registration.json";
  EXPECT_EQ(r.result["status"], "converged");
  EXPECT_EQ(r.result["fit"]["noise_model"].get<std::string>().rfind("estimated", 0), 0u) << r.result["fit"];
  ASSERT_EQ(r.result["bodies"].size(), 1u);
  const json& body = r.result["bodies"][0];
  EXPECT_EQ(body["unconstrained"].size(), 3u) << body["unconstrained"];
  EXPECT_FALSE(r.result["usable"].get<bool>()) << "a pose with free directions is called usable";
  EXPECT_EQ(r.exit_code, 1);
  ASSERT_EQ(r.result["planes"].size(), 1u);
  EXPECT_TRUE(r.result["planes"][0]["usable"].get<bool>());
  ExpectPlaneMatchesReference(r.result["planes"][0], ReferencePlane());
}

// Step 4: hold what the data cannot see; the run is then usable and exits 0, same plane.
TEST(RealCloudWalkthrough, FixingTheFreeDirectionsMakesItUsable) {
  const CliRun r = RunRegister("fixed", "--fix wall:y,z,rx");
  ASSERT_FALSE(r.result.is_null()) << "no registration.json";
  EXPECT_TRUE(r.result["usable"].get<bool>()) << r.result["warnings"];
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(r.result["bodies"][0]["unconstrained"].empty());
  ExpectPlaneMatchesReference(r.result["planes"][0], ReferencePlane());
}

}  // namespace
}  // namespace ifab
