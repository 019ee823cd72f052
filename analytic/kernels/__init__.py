"""The kernels both analytic engines share: the smooth forces of the plan model and the Takeda
(OpenSees ``Hysteretic``) clone, contact kinematics, the compliant contact laws and their
assembly on the DOF, support motion at the engine's step, peaks, dense linear algebra and the
LCP solvers (numba)."""
