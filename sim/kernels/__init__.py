"""numba kernels of the simulator (four-bar, slider-crank), one module per piece of physics.

* ``_layout``: indices into the parameter vectors, the diagnostics row, the info array and the context;
* ``_jit``: how the evaluation kernels are compiled (cached, without numba's runtime: they
  allocate nothing);
* ``_context``: the evaluation context, with the scratch arrays the kernels work in, made once
  per integration;
* ``_geometry``: follower rotation, bore/journal nodes, contact search, layer axes, a force
  added to a contact wrench;
* ``_friction``: smoothed Coulomb friction (eq. 12);
* ``_contact``: Lankarani-Nikravesh contact forces (eqs. 6-10), wear work, impact latch;
* ``_tilt``: the lumped tilt spring-damper of the clearance joint (``joint.tilt_stiffness``);
* ``_joint``: the clearance joint's side of the mechanism interface (poses in, wrench out), the
  joint's frames between a spatial and a planar body, and its slots of the diagnostics row
  (clearance and ideal joint), written once for every mechanism;
* ``_equations``: equations of motion of the four-bar's clearance and ideal models, and the
  dispatch to the mechanism (``IP[MECH]``);
* ``_slider_crank``, ``_slider_kinematics``: the slider-crank's equations of motion and its
  closed-form kinematics;
* ``_integrator``: DOPRI5 integration with output times.

Everything here works on plain float arrays; :mod:`jointwear.sim.dynamics` packs the parameters
(the index constants of ``_layout``) and unpacks the results. Units are SI throughout. njit
functions call each other across these modules.

State vector, clearance model (11): theta1, theta2, theta1_dot, theta2_dot, q_w, q_x, q_y, q_z
(follower orientation, body -> global), omega_x, omega_y, omega_z (follower angular velocity in
its body frame). Ideal model (6): theta1, theta2, theta3, and their rates. The slider-crank's
states: :mod:`._slider_crank`.
"""
