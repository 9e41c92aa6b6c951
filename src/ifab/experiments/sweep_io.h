#pragma once
/// \file
/// Recorded arm sweeps, for `ifab calibrate` and for keeping data: one JSON file per sweep (one
/// joint moving while the arm laser scans). Read and written here, outside the algorithm modules
/// (which link no JSON library); the recording itself is perception/sweep_recording.h.
///
/// Format (version 1):
///
///     {
///       "format": "ifab-sweep", "version": 1, "name": "joint 5 up",
///       "scans": [                        // arm laser scans, in time order
///         {"t": 12.500,                   // host time [s] of beam 0 (after clock sync)
///          "angle_min": -2.35619, "angle_increment": 0.00436332,   // [rad]
///          "time_increment": 1.7361e-05,  // [s] between beams
///          "range_min": 0.1, "range_max": 30.0,                    // [m]
///          "ranges": [1.234, null, ...]}, // [m]; null = no return
///         ...],
///       "joint_states": [                 // arm joint angles, any rate (the IF: 250 Hz)
///         {"t": 12.496, "q": [q1, q2, q3, q4, q5, q6]}, ...]      // host time [s], [rad]
///     }
///
/// Raw device time stamps may be given instead of host times: then every scan and joint state
/// has "t_device" and "sequence" (no "t"), and the file has
///     "sync_pulses": [{"device": "arm_laser" | "arm", "sequence": 17, "t_host": 12.49}, ...]
/// and the loader maps device times to host time with the sync module (TICSync-style).

#include <iosfwd>
#include <string>
#include <vector>

#include "ifab/perception/sweep_recording.h"

namespace ifab {

/// Read a sweep file; host times are filled in (from the pulses if the file has raw stamps).
/// Throws InputError naming the file and the field that is wrong.
SweepRecording LoadSweep(const std::string& path);
/// The same from a stream; `name` stands for the file in messages.
SweepRecording ParseSweep(std::istream& in, const std::string& name);

/// The sweep in the file format above (host times; pulses and device stamps too if
/// `raw_stamps`) to a stream; experiments/perception_json.h's SaveSweep writes the file.
void WriteSweep(std::ostream& out, const SweepRecording& sweep, bool raw_stamps = false);

}  // namespace ifab
