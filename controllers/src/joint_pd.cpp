// Joint PD gain-scale randomisation (the controller itself is a template in joint_pd.hpp).
#include "kestrel/controllers/joint_pd.hpp"

namespace kestrel {

JointGainScales randomize_joint_gain_scales(const JointGainScaleRanges& r, RngStream& rng) {
  JointGainScales s;
  s.kp_scale = rng.uniform(r.kp_scale_min, r.kp_scale_max);
  s.kd_scale = rng.uniform(r.kd_scale_min, r.kd_scale_max);
  return s;
}

JointGainScales joint_nominal_gain_scales(const JointGainScaleRanges& r) {
  JointGainScales s;
  s.kp_scale = (r.kp_scale_max + r.kp_scale_min) / 2;
  s.kd_scale = (r.kd_scale_max + r.kd_scale_min) / 2;
  return s;
}

}  // namespace kestrel

namespace kestrel {

// One instantiation compiled with the core's flags (-Wdouble-promotion, no exceptions on the MCU),
// so the template is checked even when only tests instantiate it: 12 joints (a quadruped), 4 steps.
template Status validate_joint_pd_params<12, 4>(const JointPdParams<12, 4>&);
template void joint_pd_reset<12, 4>(const JointPdParams<12, 4>&, JointPdState<12, 4>&);
template void joint_pd_reset<12, 4>(const JointPdParams<12, 4>&, JointPdState<12, 4>&, RngStream&);
template Status update_joint_pd<12, 4>(const JointPdParams<12, 4>&, JointPdState<12, 4>&, const real*, const real*,
                                       const real*, real*);

}  // namespace kestrel
