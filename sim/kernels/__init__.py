"""numba kernels of the four-bar simulator, one module per piece of physics.

* ``_layout``: indices into the parameter vectors, the diagnostics row and the info array;
* ``_geometry``: follower rotation, bore/journal nodes, contact search, layer axes;
* ``_friction``: smoothed Coulomb friction (eq. 12);
* ``_contact``: Lankarani-Nikravesh contact forces (eqs. 6-10), wear work, impact latch;
* ``_equations``: equations of motion of the clearance and ideal models;
* ``_integrator``: DOPRI5 integration with output times.

Everything here works on plain float arrays; :mod:`jointwear.sim.dynamics` packs the parameters
(the index constants of ``_layout``) and unpacks the results. Units are SI throughout. njit
functions call each other across these modules.

State vector, clearance model (11): theta1, theta2, theta1_dot, theta2_dot, q_w, q_x, q_y, q_z
(follower orientation, body -> global), omega_x, omega_y, omega_z (follower angular velocity in
its body frame). Ideal model (6): theta1, theta2, theta3, and their rates.
"""
