#pragma once
/// \file
/// Registration and calibration results as JSON, for the experiments' results.json and the
/// `ifab register` / `ifab calibrate` outputs (the algorithm module itself writes no files).

#include <nlohmann/json.hpp>

#include "ifab/core/se3.h"
#include "ifab/perception/calibration.h"
#include "ifab/perception/registration.h"
#include "ifab/experiments/sweep_io.h"

namespace ifab {

/// A pose as JSON: {"xyz": [m], "rpy_deg": [deg], "matrix": 4 rows of 4}.
nlohmann::json PoseToJson(const Pose3& pose);
/// A matrix as rows.
nlohmann::json MatrixToJson(const Eigen::MatrixXd& m);
/// Standard deviations of a [x y z rx ry rz] covariance: {"xyz_mm": [...], "rotation_deg": [...]}.
nlohmann::json StdToJson(const Matrix6d& covariance);
/// One registered body: name, pose, covariance, std, inliers, unconstrained and held directions.
nlohmann::json BodyToJson(const RegisteredBody& body, bool usable);
/// The noise model used and the test of the fit (fit_quality.h).
nlohmann::json FitToJson(const FitQuality& fit);
/// How far the calibration took the ground as one plane, and the rings that said so.
nlohmann::json GroundExtentToJson(const GroundExtent& extent);

/// Write a sweep file (experiments/sweep_io.h's format), in full or not at all.
void SaveSweep(const std::string& path, const SweepRecording& sweep, bool raw_stamps = false);

}  // namespace ifab
