// `make bench-peers`: ifab beside its peers on the same inputs, in one run, one table.
//  - registration: sweeps of the brick stack as the brick-stack mission takes them (the stack
//    at each of its heights, seen from the building positions in the mission's order, along a
//    brick diagonal from 0.8 m at 50 deg elevation, +-12 deg of sweep), synthesised by ray casting
//    with the laser's noise and mixed pixels; each registered from a guess 2 cm / 2 deg off with
//    ifab (the mission's options) and with Open3D's point-to-plane ICP and generalized ICP against
//    the model sampled densely at the guess. Error of the stack's pose against the truth.
//  - base planning: the 500 cases of `ifab run base-planning`, planned by STOMP and by OMPL
//    (RRT-Connect in a Reeds-Shepp space, forwards and in reverse, the same footprint checker as
//    validity check, path simplified, a time limit), every OMPL path re-checked densely.
//  - dynamics: KDL's recursive Newton-Euler solvers against ifab's on random states.
// Times are single-thread CPU times (see Clock). Built only where Open3D and OMPL are installed
// (scripts/install-deps --with-peers); not part of `make test` or `make bench`.

#include <fmt/format.h>
#include <open3d/Open3D.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/spaces/ReedsSheppStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <string>
#include <vector>

#include "ifab/arm/arm_model.h"
#include "ifab/arm/dynamics.h"
#include "ifab/experiments/base_planning_experiment.h"
#include "ifab/base/planner/site_scene.h"
#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/random.h"
#include "ifab/model/robot_model.h"
#include "ifab/model/site.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/testing/synthetic.h"
#include "ifab/sim/as_built.h"
#include "ifab/sim/lrf_model.h"
#include "ifab/sim/sim_robot.h"
#include "perception_scene.h"

namespace ifab {
namespace {

// Times are the CPU time of the process with every library on one thread (OMP_NUM_THREADS=1 is
// set before Open3D starts its OpenMP pool): on a loaded machine wall times mostly measure the
// load, CPU times the work.
struct Clock {
  using time_point = double;
  static double now() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  }
};
double Since(double t0) { return Clock::now() - t0; }

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(std::floor(pos));
  const std::size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (pos - static_cast<double>(i)) * (v[j] - v[i]);
}
double Worst(const std::vector<double>& v) { return v.empty() ? std::nan("") : *std::max_element(v.begin(), v.end()); }

struct Row {
  std::string work, figure, ifab, peer_name, peer;
  double ratio{std::nan("")};  // ifab / peer
};
std::vector<Row> rows;

void Add(const std::string& work, const std::string& figure, double ours, const std::string& peer_name, double peer,
         const char* format = "{:.3g}") {
  rows.push_back({work, figure, fmt::format(fmt::runtime(format), ours), peer_name,
                  fmt::format(fmt::runtime(format), peer), peer != 0.0 ? ours / peer : std::nan("")});
}

// ---------------------------------------------------------------------------------- registration

struct Sweep {
  std::vector<RegistrationBody> truth, guess;  // "ground", "site" (the stack as built)
  std::vector<RayPoint> cloud;
  std::vector<RayPoint> full;  // the whole sweep, before the crop
  Eigen::Vector3d p_stack_base;
};

// The arm laser the sweeps are synthesised with: "paper", the UTM-30LX of the paper and DESIGN.md
// (18 mm along the ray at every range: the exact world's laser), or "as-built", the unit the
// default (as-built) brick-stack world draws (data/sim/as_built.yaml `lasers:`: noise growing from
// 5 mm at 0.1 m to 18 mm at 2 m and with incidence, Pomerleau et al. 2012; the law at the centre
// of the drawn units). Neither adds a range bias: the truth of a registration stays defined.
std::string laser_model = "as-built";

testing::SyntheticLaser ArmLaser() {
  testing::SyntheticLaser laser;
  laser.mixed_pixels = true;
  if (laser_model == "as-built") {
    const sim::SimOptions machine =
        sim::SimOptions::FromConfig(ConfigNode::LoadFile(IFAB_DATA_DIR "/sim/insitu_fabricator.yaml")["sim"]);
    const sim::AsBuiltTolerances tolerances = sim::AsBuiltTolerances::Load(IFAB_DATA_DIR "/sim/as_built.yaml");
    // The units' law itself (a unit scale of 1, the centre of the drawn units), not one lucky draw.
    sim::LrfOptions unit = machine.arm_laser;
    unit.sigma_along_range_m = tolerances.laser.sigma_along_range_m;
    unit.sigma_along_table_m = tolerances.laser.sigma_along_m;
    unit.sigma_incidence_gain = tolerances.laser.sigma_incidence_gain;
    laser.sigma_along_at = [unit](double range, double incidence) { return unit.SigmaAlong(range, incidence); };
  }
  return laser;
}

std::vector<Sweep> MakeSweeps(int count) {
  Site site = LoadSite(IFAB_DATA_DIR "/sites/brick_stack.yaml");
  site.walls.clear();  // the mission registers to the workpiece and the ground only
  site.obstacles.clear();
  const std::vector<Pose2> positions = {{-1.9, -0.3, DegToRad(9.0)},
                                        {-1.1, 1.6, DegToRad(-55.5)},
                                        {1.1, 1.6, DegToRad(-124.5)},
                                        {1.9, -0.3, DegToRad(171.0)}};
  RandomStream rng(20260101);
  const testing::SyntheticLaser laser = ArmLaser();  // loads its YAML once, not per sweep
  std::vector<Sweep> out;
  for (int v = 0; v < count; ++v) {
    // Visit v + 1 of the mission: the stack has v + 2 bricks (one placed per visit, 26 in all).
    const int bricks = std::min(v + 2, 26);
    site.bricks.clear();
    for (int k = 0; k < bricks; ++k) site.bricks.push_back({"brick", site.DesignedBrickPose(k), site.brick});
    const Pose2& position = positions[static_cast<std::size_t>((v + 1) % 4)];
    // Where the robot really stands (within 1 cm / 0.5 deg of the building position) and where
    // it believes it stands (2 cm / 2 deg off that, random directions).
    const double dtheta = DegToRad(rng.Uniform(-0.5, 0.5));  // last first: gcc's order of the arguments
    const double dy = rng.Uniform(-0.01, 0.01), dx = rng.Uniform(-0.01, 0.01);
    const Pose2 true_pose(position.x + dx, position.y + dy, position.theta + dtheta);
    const double a = rng.Uniform(0.0, 2 * M_PI);
    const Pose2 guess_pose(true_pose.x + 0.02 * std::cos(a), true_pose.y + 0.02 * std::sin(a),
                           true_pose.theta + DegToRad(rng.Uniform(0.0, 1.0) < 0.5 ? -2.0 : 2.0));
    const Pose3 T_site_base = PoseFromXyzRpy(true_pose.x, true_pose.y, 0.0, 0.0, 0.0, true_pose.theta);
    const Pose3 T_site_base_guess = PoseFromXyzRpy(guess_pose.x, guess_pose.y, 0.0, 0.0, 0.0, guess_pose.theta);
    Sweep s;
    s.truth = SiteBodies(site, T_site_base, true);
    s.guess = SiteBodies(site, T_site_base_guess, true);
    // The mission's view: along the brick diagonal nearest the robot, 0.8 m from the top, 50 deg up.
    const SiteBox& top = site.bricks.back();
    const Eigen::Vector3d p_top = top.T_site_box * Eigen::Vector3d(0, 0, 0.5 * top.box.size.z());
    const Eigen::Vector2d to_robot = (T_site_base.translation() - p_top).head<2>().normalized();
    const double brick_yaw = XyzRpyFromPose(top.T_site_box)[5];
    Eigen::Vector2d diagonal = to_robot;
    double best = -2.0;
    for (int k = 0; k < 4; ++k) {
      const double b = brick_yaw + M_PI / 4 + k * M_PI / 2;
      const Eigen::Vector2d d(std::cos(b), std::sin(b));
      if (d.dot(to_robot) > best) best = d.dot(to_robot), diagonal = d;
    }
    const double el = DegToRad(50.0);
    const Eigen::Vector3d p_laser = p_top + 0.8 * Eigen::Vector3d(std::cos(el) * diagonal.x(), std::cos(el) * diagonal.y(), std::sin(el));
    const Pose3 T_base_site = T_site_base.inverse();
    const Scene world(s.truth);
    auto laser_at = [&](double t) {
      // The scan fan is vertical through the look direction; the sweep turns it about the vertical.
      const double yaw = DegToRad(-12.0 + 8.0 * t);
      const Eigen::Matrix3d Rz = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      const Eigen::Vector3d look = Rz * (p_top - p_laser).normalized();
      const Eigen::Vector3d z = look.cross(Eigen::Vector3d::UnitZ()).normalized();
      Pose3 T_site_laser = Pose3::Identity();
      T_site_laser.linear().col(0) = look;
      T_site_laser.linear().col(1) = z.cross(look);
      T_site_laser.linear().col(2) = z;
      T_site_laser.translation() = p_laser;
      return Pose3(T_base_site * T_site_laser);
    };
    const std::vector<RayPoint> swept = testing::SynthesizeCloud(world, laser_at, 0.0, 3.0, laser, rng);
    s.p_stack_base = T_base_site * p_top;
    for (const RayPoint& p : swept)
      if ((p.p - s.p_stack_base).head<2>().norm() < 0.6) s.cloud.push_back(p);  // the mission's crop
    s.full = swept;
    out.push_back(std::move(s));
  }
  return out;
}

const RegistrationBody& Stack(const std::vector<RegistrationBody>& bodies) { return bodies[1]; }

// Does ifab leave information of the sweep unused? The same sweeps registered with each rule
// that drops or down-weights points switched off, with the whole sweep instead of the mission's
// crop, and with the ground and the stack as one rigid body (the model the peers get: the floor
// then pins the stack's height and tilt): if one of them lowered the error (and the error its
// covariance predicts), the default would be below the sweep's information limit. Printed as its
// own table.
void RegistrationInformationRows(int count) {
  const std::vector<Sweep> sweeps = MakeSweeps(count);
  const RegistrationOptions base =
      RegistrationOptions::FromConfig(ConfigNode::LoadFile(IFAB_DATA_DIR "/perception/perception.yaml")["registration"]);
  struct Variant {
    std::string name;
    RegistrationOptions options;
    bool full{false};
    bool one_body{false};  // the ground's parts joined to the stack's body
  };
  std::vector<Variant> variants{{"default (perception.yaml, the mission's 0.6 m crop)", base, false}};
  variants.push_back({"no shadow-point rule", base, false});
  variants.back().options.shadow_points = false;
  variants.push_back({"no robust loss (every point at full weight)", base, false});
  variants.back().options.loss = RobustLoss::kNone;
  variants.push_back({"max_distance 0.5 m (instead of 0.15)", base, false});
  variants.back().options.max_distance = 0.5;
  variants.push_back({"the noise scale estimated from the residuals (noise_source: estimated)", base, false});
  variants.back().options.noise_source = NoiseSource::kEstimated;
  variants.push_back({"the whole sweep (no crop)", base, true});
  variants.push_back({"the ground and the stack one rigid body (as the peers' model)", base, false, true});
  std::puts("| ifab variant | points / inliers (median) | error median / worst [mm] | predicted median [mm] | error / predicted (median) | time median [ms] |");
  std::puts("|---|---|---|---|---|---|");
  for (const Variant& v : variants) {
    std::vector<double> mm, predicted, ratio, ms, points, inliers;
    for (const Sweep& s : sweeps) {
      const auto& cloud = v.full ? s.full : s.cloud;
      const double t0 = Clock::now();
      std::vector<RegistrationBody> bodies = s.guess;
      if (v.one_body) {  // both bodies are at T_base_site
        bodies[1].parts.insert(bodies[1].parts.end(), bodies[0].parts.begin(), bodies[0].parts.end());
        bodies.erase(bodies.begin());
      }
      const RegistrationSummary r = Register(cloud, bodies, v.options);
      ms.push_back(1e3 * Since(t0));
      const std::size_t k = v.one_body ? 0 : 1;  // the stack's body
      const Pose3& est = r.IsUsable() ? r.bodies[k].T_base_body : Stack(s.guess).T_base_body;
      mm.push_back(1e3 * TranslationDistance(est, Stack(s.truth).T_base_body));
      points.push_back(r.num_points);
      inliers.push_back(r.num_inliers);
      if (r.IsUsable()) {
        predicted.push_back(1e3 * std::sqrt(r.bodies[k].covariance.topLeftCorner<3, 3>().trace()));
        ratio.push_back(mm.back() / predicted.back());
      }
    }
    std::printf("| %s | %.0f / %.0f | %.2f / %.2f | %.2f | %.2f | %.0f |\n", v.name.c_str(), Quantile(points, 0.5),
                Quantile(inliers, 0.5), Quantile(mm, 0.5), Worst(mm), Quantile(predicted, 0.5), Quantile(ratio, 0.5),
                Quantile(ms, 0.5));
  }
}

void RegistrationRows(int count) {
  namespace reg = open3d::pipelines::registration;
  const std::vector<Sweep> sweeps = MakeSweeps(count);
  const RegistrationOptions options =
      RegistrationOptions::FromConfig(ConfigNode::LoadFile(IFAB_DATA_DIR "/perception/perception.yaml")["registration"]);
  struct Method {
    std::string name;
    std::vector<double> ms{}, mm{}, deg{};
  };
  Method ours{"ifab", {}, {}, {}}, icp{"Open3D point-to-plane ICP", {}, {}, {}}, gicp{"Open3D generalized ICP", {}, {}, {}};
  auto score = [](Method& m, const Pose3& est, const Pose3& truth, double seconds) {
    m.ms.push_back(1e3 * seconds);
    m.mm.push_back(1e3 * TranslationDistance(est, truth));
    m.deg.push_back(RadToDeg(RotationAngle(est, truth)));
  };
  std::size_t points = 0, model_points = 0;
  std::vector<double> predicted_mm, normalized;
  for (const Sweep& s : sweeps) {
    points += s.cloud.size();
    const Pose3& truth = Stack(s.truth).T_base_body;
    const Pose3& guess = Stack(s.guess).T_base_body;
    auto t0 = Clock::now();
    const RegistrationSummary r = Register(s.cloud, s.guess, options);
    score(ours, r.IsUsable() ? r.bodies[1].T_base_body : guess, truth, Since(t0));
    // What ifab's own covariance predicts for that error (the RMS length of a 3-D Gaussian
    // translation error is sqrt of the trace): how close the data's information lets any fit come.
    if (r.IsUsable()) {
      predicted_mm.push_back(1e3 * std::sqrt(r.bodies[1].covariance.topLeftCorner<3, 3>().trace()));
      normalized.push_back(ours.mm.back() / predicted_mm.back());
    }

    // Open3D: the model every 2 mm over the stack's faces and the floor around it, at the guess.
    const bench::OrientedPoints model = bench::SampleSurfaces(s.guess, 0.002, s.p_stack_base, 0.6);
    model_points += model.points.size();
    open3d::geometry::PointCloud source, target;
    target.points_ = model.points;
    target.normals_ = model.normals;
    for (const auto& p : s.cloud) source.points_.push_back(p.p);
    // ICP moves the cloud onto the model: T p_true = p_guess, so the stack is at T^-1 T_base_guess.
    auto estimate = [&](const reg::RegistrationResult& res) {
      Pose3 T = Pose3::Identity();
      T.matrix() = res.transformation_;
      return Pose3(T.inverse() * guess);
    };
    const reg::ICPConvergenceCriteria criteria(1e-8, 1e-8, 100);
    t0 = Clock::now();
    const auto res_icp = reg::RegistrationICP(source, target, 0.05, Eigen::Matrix4d::Identity(),
                                              reg::TransformationEstimationPointToPlane(), criteria);
    score(icp, estimate(res_icp), truth, Since(t0));
    t0 = Clock::now();
    const auto res_gicp = reg::RegistrationGeneralizedICP(source, target, 0.05, Eigen::Matrix4d::Identity(),
                                                          reg::TransformationEstimationForGeneralizedICP(), criteria);
    score(gicp, estimate(res_gicp), truth, Since(t0));
  }
  const std::string work = fmt::format("registration, {} sweeps (~{}k points; model {}k points; {} laser)",
                                       sweeps.size(), points / sweeps.size() / 1000, model_points / sweeps.size() / 1000,
                                       laser_model);
  rows.push_back({work, "ifab: error its covariance predicts, median [mm]; median of error / predicted",
                  fmt::format("{:.2f}; {:.2f}", Quantile(predicted_mm, 0.5), Quantile(normalized, 0.5)), "-", "", std::nan("")});
  // The better peer by median error.
  for (const Method* peer : {&icp, &gicp}) {
    Add(work, "error median [mm]", Quantile(ours.mm, 0.5), peer->name, Quantile(peer->mm, 0.5), "{:.2f}");
    Add(work, "error worst [mm]", Worst(ours.mm), peer->name, Worst(peer->mm), "{:.2f}");
    Add(work, "error median [deg]", Quantile(ours.deg, 0.5), peer->name, Quantile(peer->deg, 0.5), "{:.3f}");
    Add(work, "error worst [deg]", Worst(ours.deg), peer->name, Worst(peer->deg), "{:.3f}");
    Add(work, "time median [ms]", Quantile(ours.ms, 0.5), peer->name, Quantile(peer->ms, 0.5), "{:.1f}");
    Add(work, "time worst [ms]", Worst(ours.ms), peer->name, Worst(peer->ms), "{:.1f}");
  }
}

// ---------------------------------------------------------------------------------- planning

void PlanningRows(double time_limit) {
  namespace ob = ompl::base;
  namespace og = ompl::geometric;
  const ConfigNode experiment = ConfigNode::LoadFile(IFAB_DATA_DIR "/experiments/base-planning.yaml");
  const Site site = LoadSite(IFAB_DATA_DIR "/sites/brick_stack.yaml");
  const base::BaseGeometry robot = base::BaseGeometry::Load(IFAB_DATA_DIR "/robots/insitu_fabricator_base.yaml");
  base::StompPlannerOptions stomp =
      base::StompPlannerOptions::FromConfig(ConfigNode::LoadFile(IFAB_DATA_DIR "/base/planner.yaml")["base_planner"]);
  stomp.num_threads = 1;
  experiments::BasePlanningExperimentOptions sampling = experiments::BasePlanningExperimentOptions::FromConfig(experiment["sampling"]);
  sampling.cases = experiment["cases"].As<int>();
  sampling.seed = experiment["seed"].As<std::uint64_t>();
  const base::StompBasePlanner planner(base::PlanningSceneFromSite(site), robot, stomp);
  std::vector<experiments::BasePlanningCase> cases;
  experiments::RunBasePlanningExperiment(planner, sampling, &cases);
  const base::FootprintChecker& checker = planner.checker();

  ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
  ompl::RNG::setSeed(1);  // before any sampler exists, so the run repeats
  // Reeds-Shepp: a car that reverses; a turning radius well below the footprint (tracks can turn
  // on the spot, which Reeds-Shepp cannot express).
  auto space = std::make_shared<ob::ReedsSheppStateSpace>(0.3);
  ob::RealVectorBounds bounds(2);
  Eigen::Vector2d lo = site.boundary.front(), hi = lo;
  for (const auto& p : site.boundary) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  bounds.setLow(0, lo.x());
  bounds.setHigh(0, hi.x());
  bounds.setLow(1, lo.y());
  bounds.setHigh(1, hi.y());
  space->setBounds(bounds);
  og::SimpleSetup ss(space);
  auto pose_of = [](const ob::State* s) {
    const auto* se2 = s->as<ob::SE2StateSpace::StateType>();
    return Pose2(se2->getX(), se2->getY(), se2->getYaw());
  };
  ss.setStateValidityChecker([&](const ob::State* s) { return checker.Clearance(pose_of(s)) >= 0.0; });
  // Motion checks every 0.5 % of the space's extent (~5 cm): OMPL's usual resolution is 1 %.
  ss.getSpaceInformation()->setStateValidityCheckingResolution(0.005);
  ss.setPlanner(std::make_shared<og::RRTConnect>(ss.getSpaceInformation()));
  ss.setup();

  std::vector<double> ours_ms, peer_ms, ours_len, peer_len;
  int ours_ok = 0, peer_ok = 0;
  double ours_clear = INFINITY, peer_clear = INFINITY;
  const RandomStream root(sampling.seed);
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const auto& c = cases[k];
    // Planned again as the experiment planned it (same random stream), timed on the CPU clock.
    const auto t_plan = Clock::now();
    const base::PlanResult again = planner.Plan(c.start, c.goal, root.Derive(static_cast<std::uint64_t>(k)).Derive("planner"));
    ours_ms.push_back(1e3 * Since(t_plan));
    if (again.IsUsable() != c.result.IsUsable()) std::fprintf(stderr, "peers: case %zu planned differently the second time\n", k);
    if (c.result.IsUsable()) {
      ++ours_ok;
      ours_len.push_back(c.result.trajectory.Length());
      ours_clear = std::min(ours_clear, c.result.min_clearance);
    }
    ob::ScopedState<> start(space), goal(space);
    start[0] = c.start.x, start[1] = c.start.y, start[2] = c.start.theta;
    goal[0] = c.goal.x, goal[1] = c.goal.y, goal[2] = c.goal.theta;
    ss.clear();
    ss.setStartAndGoalStates(start, goal);
    const auto t0 = Clock::now();
    const ob::PlannerStatus solved = ss.solve(time_limit);
    bool ok = solved == ob::PlannerStatus::EXACT_SOLUTION;
    if (ok) ss.simplifySolution();
    peer_ms.push_back(1e3 * Since(t0));
    if (!ok) continue;
    // Re-check the path at 5 mm with the same checker; its clearance is the path's.
    og::PathGeometric path = ss.getSolutionPath();
    const double length = path.length();
    path.interpolate(static_cast<unsigned>(std::ceil(length / 0.005)) + 2);
    double clearance = INFINITY;
    for (const ob::State* s : path.getStates()) clearance = std::min(clearance, checker.Clearance(pose_of(s)));
    if (clearance < 0.0) continue;
    ++peer_ok;
    peer_len.push_back(length);
    peer_clear = std::min(peer_clear, clearance);
  }
  const std::string work = fmt::format("base planning, {} cases of `ifab run base-planning`", cases.size());
  const std::string peer = fmt::format("OMPL RRT-Connect, Reeds-Shepp r 0.3 m, limit {:.1f} s", time_limit);
  const double n = static_cast<double>(cases.size());
  Add(work, "success rate", ours_ok / n, peer, peer_ok / n, "{:.3f}");
  Add(work, "time median [ms]", Quantile(ours_ms, 0.5), peer, Quantile(peer_ms, 0.5), "{:.2f}");
  Add(work, "time p95 [ms]", Quantile(ours_ms, 0.95), peer, Quantile(peer_ms, 0.95), "{:.2f}");
  Add(work, "path length median [m]", Quantile(ours_len, 0.5), peer, Quantile(peer_len, 0.5), "{:.2f}");
  // In mm: both planners' closest paths touch their margin, and metres at 3 decimals printed both
  // as 0.000 beside a ratio of 15.
  Add(work, "min clearance [mm]", 1e3 * ours_clear, peer, 1e3 * peer_clear, "{:.2f}");
}

// ---------------------------------------------------------------------------------- dynamics

void DynamicsRows(int samples) {
  const RobotModel robot_model = LoadRobotModel(IFAB_DATA_DIR "/robots/insitu_fabricator.urdf");
  const arm::ArmModel model = arm::ArmModel::FromRobotModel(robot_model);
  const KDL::Chain& chain = robot_model.arm_chain;
  KDL::ChainIdSolver_RNE id(chain, KDL::Vector(0, 0, -9.81));
  KDL::ChainFdSolver_RNE fd(chain, KDL::Vector(0, 0, -9.81));
  const KDL::Wrenches no_wrench(chain.getNrOfSegments(), KDL::Wrench::Zero());
  RandomStream rng(7);
  struct State {
    Vector6d q, qd, qdd, tau;
  };
  std::vector<State> states(static_cast<std::size_t>(samples));
  for (auto& s : states)
    for (int i = 0; i < 6; ++i) {
      s.q[i] = rng.Uniform(-2.0, 2.0);
      s.qd[i] = rng.Uniform(-1.0, 1.0);
      s.qdd[i] = rng.Uniform(-3.0, 3.0);
      s.tau[i] = rng.Uniform(-500.0, 500.0);
    }
  auto to_kdl = [](const Vector6d& v) {
    KDL::JntArray a(6);
    a.data = v;
    return a;
  };
  std::vector<KDL::JntArray> q(states.size()), qd(states.size()), qdd(states.size()), tau(states.size());
  for (std::size_t k = 0; k < states.size(); ++k) {
    q[k] = to_kdl(states[k].q), qd[k] = to_kdl(states[k].qd), qdd[k] = to_kdl(states[k].qdd), tau[k] = to_kdl(states[k].tau);
  }
  arm::ArmData data;
  KDL::JntArray out(6);
  double worst_id = 0.0, worst_fd = 0.0, sink = 0.0;
  // Inverse dynamics.
  auto t0 = Clock::now();
  for (std::size_t k = 0; k < states.size(); ++k)
    sink += arm::InverseDynamics<double>(model, data, states[k].q, states[k].qd, states[k].qdd, model.gravity)[0];
  const double ours_id = Since(t0);
  t0 = Clock::now();
  for (std::size_t k = 0; k < states.size(); ++k) {
    id.CartToJnt(q[k], qd[k], qdd[k], no_wrench, out);
    sink += out(0);
  }
  const double kdl_id = Since(t0);
  for (std::size_t k = 0; k < states.size(); ++k) {
    const Vector6d ours = arm::InverseDynamics<double>(model, data, states[k].q, states[k].qd, states[k].qdd, model.gravity);
    id.CartToJnt(q[k], qd[k], qdd[k], no_wrench, out);
    worst_id = std::max(worst_id, (ours - out.data).cwiseAbs().maxCoeff());
  }
  // Forward dynamics.
  t0 = Clock::now();
  for (std::size_t k = 0; k < states.size(); ++k) {
    arm::ForwardDynamics<double>(model, data, states[k].q, states[k].qd, states[k].tau, model.gravity);
    sink += data.qdd[0];
  }
  const double ours_fd = Since(t0);
  t0 = Clock::now();
  for (std::size_t k = 0; k < states.size(); ++k) {
    fd.CartToJnt(q[k], qd[k], tau[k], no_wrench, out);
    sink += out(0);
  }
  const double kdl_fd = Since(t0);
  for (std::size_t k = 0; k < states.size(); ++k) {
    arm::ForwardDynamics<double>(model, data, states[k].q, states[k].qd, states[k].tau, model.gravity);
    fd.CartToJnt(q[k], qd[k], tau[k], no_wrench, out);
    worst_fd = std::max(worst_fd, (data.qdd - out.data).cwiseAbs().maxCoeff());
  }
  const double n = static_cast<double>(states.size());
  const std::string work = fmt::format("arm dynamics, {} random states", states.size());
  Add(work, "inverse dynamics [us]", 1e6 * ours_id / n, "KDL ChainIdSolver_RNE", 1e6 * kdl_id / n, "{:.2f}");
  Add(work, "forward dynamics [us]", 1e6 * ours_fd / n, "KDL ChainFdSolver_RNE", 1e6 * kdl_fd / n, "{:.2f}");
  rows.push_back({work, "largest difference: torque [N m] / acceleration [rad/s^2]", fmt::format("{:.1e} / {:.1e}", worst_id, worst_fd),
                  "KDL", "", std::nan("")});
  if (sink == 12345.678) std::puts("");  // keep the loops
}

}  // namespace
}  // namespace ifab

int main(int argc, char** argv) {
  int sweeps = 24, samples = 20000;
  double time_limit = 1.0;
  std::string only;  // empty: all three parts
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* name) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "peers: %s needs a value\n", name);
        std::exit(2);
      }
      return std::string(argv[++i]);
    };
    try {
      if (a == "--sweeps") sweeps = std::stoi(value("--sweeps"));
      else if (a == "--ompl-time-limit") time_limit = std::stod(value("--ompl-time-limit"));
      else if (a == "--dynamics-samples") samples = std::stoi(value("--dynamics-samples"));
      else if (a == "--laser") {
        ifab::laser_model = value("--laser");
        if (ifab::laser_model != "as-built" && ifab::laser_model != "paper") {
          std::fprintf(stderr, "peers: --laser: expected as-built or paper, got '%s'\n", ifab::laser_model.c_str());
          return 2;
        }
      }
      else if (a == "--only") {
        only = value("--only");
        if (only != "registration" && only != "planning" && only != "dynamics" && only != "registration-information") {
          std::fprintf(stderr, "peers: --only: expected registration, planning, dynamics or registration-information, got '%s'\n", only.c_str());
          return 2;
        }
      }
      else if (a == "-h" || a == "--help") {
        std::puts("peers [--sweeps N (24)] [--ompl-time-limit S (1.0)] [--dynamics-samples N (20000)]\n"
                  "      [--laser as-built|paper (as-built: the default world's drawn unit; paper: 18 mm at any range)]\n"
                  "      [--only registration|planning|dynamics|registration-information]\n"
                  "(registration-information: ifab alone on the same sweeps, with each rule that drops or\n"
                  " down-weights points switched off, and on the whole sweep; not part of the default run)\n"
                  "ifab beside Open3D (registration), OMPL (base planning) and KDL (dynamics) on the same inputs.");
        return 0;
      } else {
        std::fprintf(stderr, "peers: unknown argument '%s' (see --help)\n", a.c_str());
        return 2;
      }
    } catch (const std::exception&) {
      std::fprintf(stderr, "peers: %s: expected a number\n", a.c_str());
      return 2;
    }
  }
  if (sweeps < 1 || time_limit <= 0.0 || samples < 1) {
    std::fprintf(stderr, "peers: --sweeps, --ompl-time-limit and --dynamics-samples must be positive\n");
    return 2;
  }
  setenv("OMP_NUM_THREADS", "1", 1);
  using namespace ifab;
  if (only == "registration-information") {
    RegistrationInformationRows(sweeps);
    return 0;
  }
  if (only.empty() || only == "registration") {
    std::fprintf(stderr, "peers: registration of %d sweeps...\n", sweeps);
    RegistrationRows(sweeps);
  }
  if (only.empty() || only == "planning") {
    std::fprintf(stderr, "peers: base planning...\n");
    PlanningRows(time_limit);
  }
  if (only.empty() || only == "dynamics") {
    std::fprintf(stderr, "peers: dynamics...\n");
    DynamicsRows(samples);
  }
  std::puts("| work | figure | ifab | peer | peer figure | ifab / peer |");
  std::puts("|---|---|---|---|---|---|");
  for (const auto& r : rows)
    std::printf("| %s | %s | %s | %s | %s | %s |\n", r.work.c_str(), r.figure.c_str(), r.ifab.c_str(), r.peer_name.c_str(),
                r.peer.c_str(), std::isfinite(r.ratio) ? fmt::format("{:.2f}", r.ratio).c_str() : "");
  return 0;
}
