"""Parameter identification: tau = Y(q, v, a) theta from recorded joint states.

- :mod:`.regressor`: the joint-torque regressor with friction columns and the standard
  parameter vector of a Robot.
- :mod:`.base_parameters`: Gautier's numerical base parameters (QR with column pivoting).
- :mod:`.excitation`: Swevers' finite Fourier series, optimised for cond(Y_base).
- :mod:`.measurements`: /joint_states from a bag, filtered, differentiated, decimated.
- :mod:`.estimation`: ordinary and iterated weighted least squares with covariance.
- :mod:`.identify`: the pipeline from a bag to estimates; prediction RMS of any estimate.
- :mod:`.consistency`: pseudo-inertia check; a fit consistent by construction (log-Cholesky
  pseudo-inertia of every link).
- :mod:`.urdf_output`: the links of each body; the URDF with identified inertials and friction.
- :mod:`.plots`: measured vs predicted effort and residuals (PNG).
- :mod:`.synthetic`: perturbed URDFs and recorded /joint_states for round trips, through the
  dynamics node's simulation session or by inverse dynamics.
"""
