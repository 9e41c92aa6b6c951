// The paper's numbers the page draws beside ours (Sandy et al., ICRA 2016; DESIGN.md).
export const PAPER = {
  brick_long_mm: 4.6,     // mean brick error along the long face
  brick_short_mm: 3.5,    // ... along the short face
  localization_cm: 5,     // localization correction (estimator drift per maneuver)
  ilqg_iterations: 5,
  ilqg_seconds: 2,
  table1_std: [0.44, 1.05, 0.69, 0.056, 0.113, 0.717],  // registration consistency: mm, mm, mm, deg, deg, deg
  table2_std: [2.9, 1.4, 4.1, 0.389, 0.053, 0.389],     // extrinsic calibration consistency
};
