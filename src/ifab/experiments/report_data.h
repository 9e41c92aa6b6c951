#pragma once
/// \file
/// What a run writes beside results.json so that its report page (report.h) can be drawn again
/// from the run folder alone: the replay of the mission (true base pose, joint angles, gripper,
/// bricks standing, sampled as simulated time passes), when each arm laser sweep was taken, the
/// scene (site, base footprint, arm chain, building positions, designed bricks, visits) and each
/// visit's cloud with the registration's label per point (the paper's Fig. 4).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ifab/core/se2.h"
#include "ifab/sequencer/building_plan.h"
#include "ifab/sequencer/mission.h"

namespace ifab::experiments {

/// Samples of the simulated machine for the 3D replay (scoring side: experiments only).
class ReplayRecorder {
 public:
  struct Sample {
    double t{0.0};         ///< simulated time [s]
    Pose2 T_site_base;     ///< true base pose
    Vector6d q{Vector6d::Zero()};  ///< true joint angles [rad]
    bool holding{false};   ///< a brick in the gripper
    int bricks{0};         ///< bricks standing in the world
  };
  double period{0.2};  ///< [s] between samples (the page interpolates; 0.2 s keeps 26 bricks < 1 MB)

  /// Keep `s` if `period` has passed since the last kept sample.
  void Offer(const Sample& s);
  /// The arm laser switched on or off at time t (a sweep is one on-off interval).
  void ArmLaser(double t, bool active);
  /// Write DIR/replay.csv (t,x,y,theta,q1..q6,holding,bricks) and DIR/sweeps.csv (t_on,t_off).
  void Write(const std::string& dir) const;

 private:
  std::vector<Sample> samples_;
  std::vector<std::pair<double, double>> sweeps_;
  double on_{-1.0};
};

/// Write DIR/scene.json: the site (boundary, walls, obstacles, brick size), the base footprint,
/// the arm chain (for forward kinematics on the page), the building positions, the designed pose
/// of every brick of `workpiece`, and one entry per visit (times, bricks placed, localization).
void WriteSceneJson(const std::string& dir, const sequencer::MissionComponents& parts,
                    const sequencer::BuildingPlan& plan, const Site& workpiece,
                    const std::vector<sequencer::VisitLog>& logs);

/// Write DIR/scene.json with the site alone (experiments without a mission, e.g. base-planning).
void WriteSiteSceneJson(const std::string& dir, const Site& site);

/// Write a visit's assembled cloud as PLY (base frame, with the ray origins) and, when the
/// registration labelled it, a `label` field per point (0 inlier, 1 shadow, 2 outlier, 3 fixed,
/// 4 grazing; perception/registration.h).
void WriteVisitCloud(const std::string& path, const sequencer::VisitLog& log);

}  // namespace ifab::experiments
