// `ifab run faults` (issue 14): seeded short missions, each with faults drawn from the catalogue
// of sim/faults.h and injected through the simulator. The mission sees only what a real machine
// would show; this file matches what it did (its incidents) to what was injected (truth) and
// scores every brick against the stack as it truly stands.

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>

#include "ifab/core/angles.h"
#include "ifab/experiments/atomic_file.h"
#include "ifab/experiments/brick_stack_setup.h"
#include "ifab/experiments/experiments.h"
#include "ifab/experiments/sim_forwarding_robot.h"
#include "ifab/sim/faults.h"

namespace ifab::experiments {
namespace {
namespace fs = std::filesystem;

// The simulated robot behind hal::Robot, watching (truth, for scoring) whether the base ever
// touches a person the faults put in its way.
class WatchedRobot final : public SimForwardingRobot {
 public:
  explicit WatchedRobot(sim::SimRobot& sim, double length, double width)
      : SimForwardingRobot(sim), length_(length), width_(width) {}
  void Wait(Seconds dt) override {
    sim_.Wait(dt);
    CheckContact();
  }

  int contacts{0};            ///< control periods in which the footprint overlapped a person
  double closest_person{1e9}; ///< [m] closest approach of the footprint to a person

 private:
  void CheckContact() {
    const Pose2 b = sim_.true_base_pose();
    for (const SiteBox& o : sim_.world().site().obstacles) {
      if (o.name.rfind("person_", 0) != 0) continue;
      // The person's centre in the base frame against the footprint grown by the person's half size.
      const Eigen::Vector2d c = b.inverse() * Eigen::Vector2d(o.T_site_box.translation().head<2>());
      const double dx = std::max(0.0, std::abs(c.x()) - 0.5 * length_) , dy = std::max(0.0, std::abs(c.y()) - 0.5 * width_);
      const double gap = std::hypot(dx, dy) - 0.5 * o.box.size.x();
      closest_person = std::min(closest_person, gap);
      if (gap <= 0.0) ++contacts;
    }
  }
  double length_, width_;
};

// Which of the mission's incidents answer a fault, and how long after it they may come.
struct Response {
  std::vector<std::string> kinds;
  double window{30.0};  // [s] after the fault ends
};
Response ResponseTo(sim::FaultKind k, DeviceId device) {
  using K = sim::FaultKind;
  switch (k) {
    case K::kBaseLaserBlackout: return {{"base_laser_silent"}, 10.0};
    case K::kArmLaserBlackout: return {{"resweep"}, 60.0};
    case K::kDroppedScans:
      return device == DeviceId::kArmLaser ? Response{{"resweep"}, 60.0} : Response{{"base_laser_silent"}, 10.0};
    case K::kTrackSlip:
    case K::kTrackStall: return {{"replan"}, 120.0};
    case K::kGyroSpikes: return {{"gyro_spikes"}, 5.0};
    case K::kGyroBiasStep: return {{}, 0.0};
    case K::kClockJump:  // the arm laser sends only in sweeps: its jump shows at the next one
      return {{"clock_sync_reset"}, device == DeviceId::kArmLaser ? 300.0 : 60.0};
    case K::kArmTrajectoryRejected: return {{"arm_rejected"}, 5.0};
    case K::kBrickDropped: return {{"brick_lost"}, 60.0};
    case K::kStackBumped: return {{}, 0.0};
    case K::kPersonOnPath: return {{"path_blocked"}, 5.0};
    case K::kHalfSweep: return {{"resweep"}, 60.0};
  }
  return {};
}

std::string OutcomeOf(const std::string& incident_kind) {
  if (incident_kind == "arm_rejected" || incident_kind == "brick_lost" || incident_kind == "resweep" ||
      incident_kind == "replan")
    return "retried";
  return "recovered";
}

nlohmann::json RunFaults(const RunContext& ctx) {
  const auto wall_start = std::chrono::steady_clock::now();
  const ConfigNode& c = *ctx.config;
  c.ExpectKeys({"seed", "mission", "faults_per_run", "max_drive_time", "untrusted_error_mm"});
  const fs::path here = fs::path(c.file()).parent_path();
  const std::string mission_file = (here / c.Get<std::string>("mission")).string();
  sim::FaultDrawOptions draw;
  c.ReadInRange("faults_per_run", draw.faults_per_run, 1, sim::kNumFaultKinds);
  c.ReadPositive("max_drive_time", draw.max_drive_time);
  double untrusted_mm = 10.0;  // the bar: a brick this far off was placed on a pose nobody should vouch for
  c.ReadPositive("untrusted_error_mm", untrusted_mm);

  Setup setup = LoadSetup(ConfigNode::LoadFile(mission_file));
  DrawWorld(setup, ctx.seed);
  nlohmann::json mount_info = {{"source", "design"}};
  if (setup.calibrate_mount) {
    CalibrateMount(setup, ctx.seed, ctx, &mount_info);
    setup.sim_options.seconds_since_power_on = mount_info["laser_on_seconds"].get<double>();  // the lasers, warmer
  }

  RandomStream rng = RandomStream(ctx.seed).Derive("faults");
  sim::FaultInjector injector(sim::FaultInjector::Draw(rng, draw), rng.Derive("inject").seed());
  const sequencer::BuildingPlan& plan = setup.plan;
  const Pose2 start = plan.positions[static_cast<std::size_t>(plan.visits.front().position)].T_site_base;
  sim::SimRobot sim(setup.sim_options, start, setup.q0, ctx.seed);
  sim.SetFaults(&injector);
  WatchedRobot robot(sim, setup.parts.base_geometry.length, setup.parts.base_geometry.width);
  sequencer::Mission mission(robot, setup.parts, setup.mission_options, ctx.seed);
  mission.on_progress = [&](const std::string& text) { ctx.Progress(text); };
  mission.Start(start, setup.q0);
  const std::vector<sequencer::VisitLog> logs = mission.Run(plan);

  // Bricks against the stack as it truly stands (moved by every bump so far, as the bricks were).
  const auto& placed = sim.world().bricks();
  std::vector<int> placed_k;
  for (const auto& log : logs) placed_k.insert(placed_k.end(), log.bricks_placed.begin(), log.bricks_placed.end());
  int untrusted = 0;
  double worst_mm = 0.0;
  nlohmann::json bricks = nlohmann::json::array();
  for (std::size_t j = 0; j < placed_k.size() && j < placed.size(); ++j) {
    const Pose3 design = injector.T_site_stack_moved() * mission.workpiece().DesignedBrickPose(placed_k[j]);
    // Horizontal: a placed brick rests on the stack as built, so its height follows the real
    // bricks below it (EN 771-1 lets 26 of them add up to centimetres), not the pose it was
    // placed from; the height error is reported beside it.
    const Eigen::Vector3d d = placed[j].T_site_box.translation() - design.translation();
    const double e_mm = 1000.0 * d.head<2>().norm();
    worst_mm = std::max(worst_mm, e_mm);
    if (e_mm > untrusted_mm) ++untrusted;
    bricks.push_back({{"brick", placed_k[j]}, {"error_mm", e_mm}, {"height_error_mm", 1000.0 * d.z()}});
  }

  // Every fault and what the mission did about it.
  const auto& incidents = mission.incidents();
  const sequencer::Incident* stop = nullptr;
  for (const auto& i : incidents)
    if (i.kind == "safe_stop") stop = &i;
  nlohmann::json faults = nlohmann::json::array();
  int injected = 0, with_outcome = 0;
  for (const sim::FaultRecord& f : injector.records()) {
    nlohmann::json e = {{"kind", sim::FaultName(f.spec.kind)}, {"injected", f.injected}};
    if (!f.injected) {
      e["outcome"] = "not_triggered";
      e["how"] = "the mission ended before its trigger";
      faults.push_back(e);
      continue;
    }
    ++injected;
    e["detail"] = f.detail;
    e["t_start"] = f.t_start;
    e["t_end"] = f.t_end;
    const Response resp = ResponseTo(f.spec.kind, f.spec.device);
    std::vector<std::string> how;
    std::string outcome;
    for (const auto& i : incidents) {
      if (i.t < f.t_start - 0.1 || i.t > f.t_end + resp.window) continue;
      if (std::find(resp.kinds.begin(), resp.kinds.end(), i.kind) == resp.kinds.end()) continue;
      if (outcome.empty()) outcome = OutcomeOf(i.kind);
      how.push_back(i.what);
    }
    // A safe stop soon after the fault, while the mission had not recovered from it, is its outcome.
    if (stop && stop->t >= f.t_start - 0.1 && stop->t <= f.t_end + std::max(resp.window, 30.0) && outcome != "recovered") {
      outcome = "safe_stop";
      how.push_back(stop->what);
    }
    if (f.spec.kind == sim::FaultKind::kPersonOnPath && robot.contacts > 0) {
      outcome = "collision";
      how.push_back(fmt::format("the base touched the person ({} control periods)", robot.contacts));
    }
    if (outcome.empty()) {
      // Nothing to do: the closed loops took it (the next localization shows how much).
      outcome = "absorbed";
      for (const auto& log : logs)
        if (log.localized && log.t_start >= f.t_start - 60.0 && log.t_end >= f.t_start) {
          how.push_back(fmt::format("no action needed; the next localization ({}) corrected the pose by {:.1f} cm / "
                                    "{:.2f} deg",
                                    log.position, 100.0 * TranslationDistance(log.localized_pose, log.end_estimate),
                                    RadToDeg(AngleDistance(log.localized_pose, log.end_estimate))));
          break;
        }
      if (how.empty()) how.push_back("no action needed and no effect seen");
    }
    e["outcome"] = outcome;
    e["how"] = how;
    ++with_outcome;
    faults.push_back(e);
  }
  nlohmann::json incident_log = nlohmann::json::array();
  for (const auto& i : incidents) incident_log.push_back({{"t", i.t}, {"kind", i.kind}, {"what", i.what}});

  nlohmann::json r;
  r["faults"] = faults;
  r["incidents"] = incident_log;
  r["bricks"] = bricks;
  r["faults_injected"] = injected;
  r["faults_with_outcome"] = with_outcome;
  r["bricks_placed"] = static_cast<int>(placed_k.size());
  r["bricks_planned"] = plan.TotalBricks();
  r["bricks_placed_on_untrusted_pose"] = untrusted;
  r["brick_error_mm_max"] = worst_mm;
  r["person_contacts"] = robot.contacts;
  r["arm_laser_mount"] = mount_info;
  // How the run ended: all bricks placed, or a safe stop (arm parked, base still, nothing held).
  const Pose2 before = sim.true_base_pose();
  sim.Wait(1.0);
  const bool parked = (sim.true_joint_angles() - setup.mission_options.q_park).cwiseAbs().maxCoeff() < DegToRad(1.0);
  const double moved = TranslationDistance(before, sim.true_base_pose());
  const bool all_placed = static_cast<int>(placed_k.size()) >= plan.TotalBricks() && !mission.stopped();
  const bool safe = parked && moved < 1e-3 && !sim.holding_brick();
  r["ended"] = all_placed ? "placed" : (mission.stopped() ? "safe_stop" : "incomplete");
  if (mission.stopped()) r["stop_reason"] = mission.stop_reason();
  r["end_state"] = {{"arm_parked", parked}, {"base_moved_m_in_1s", moved}, {"holding_brick", sim.holding_brick()}};
  r["ended_safely"] = safe && (all_placed || mission.stopped()) ? 1 : 0;
  r["failed"] = untrusted > 0 || robot.contacts > 0 || !(safe && (all_placed || mission.stopped()));
  if (r["failed"].get<bool>())
    r["failure"] = untrusted > 0 ? "a brick was placed on an untrusted pose"
                   : robot.contacts > 0 ? "the base touched a person"
                                        : "the run did not end placed or in a safe stop";
  r["sim_seconds"] = sim.Now();
  r["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return r;
}

// Over all runs: every fault with its run, and the outcome table by kind.
nlohmann::json Summarize(const std::vector<nlohmann::json>& runs) {
  nlohmann::json all = nlohmann::json::array();
  std::map<std::string, std::map<std::string, int>> table;
  int injected = 0, untrusted = 0, contacts = 0, placed = 0, stopped = 0;
  for (const auto& run : runs) {
    if (!run.contains("faults")) continue;
    for (auto f : run["faults"]) {
      f["seed"] = run.value("seed", 0);
      if (f.value("injected", false)) {
        ++injected;
        ++table[f["kind"].get<std::string>()][f["outcome"].get<std::string>()];
      }
      all.push_back(f);
    }
    untrusted += run.value("bricks_placed_on_untrusted_pose", 0);
    contacts += run.value("person_contacts", 0);
    placed += run.value("ended", "") == "placed";
    stopped += run.value("ended", "") == "safe_stop";
  }
  return {{"faults_injected", injected},
          {"bricks_placed_on_untrusted_pose", untrusted},
          {"person_contacts", contacts},
          {"runs_ended_placed", placed},
          {"runs_ended_in_safe_stop", stopped},
          {"outcomes_by_kind", table},
          {"faults", all}};
}

}  // namespace

ExperimentInfo FaultsExperiment() {
  ExperimentInfo info;
  info.name = "faults";
  info.description = "issue 14: short missions with injected faults; every fault's outcome";
  info.run = RunFaults;
  info.summarize = Summarize;
  return info;
}

}  // namespace ifab::experiments
