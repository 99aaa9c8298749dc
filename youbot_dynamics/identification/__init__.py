"""Parameter identification: tau = Y(q, v, a) theta from recorded joint states.

- :mod:`.regressor`: the joint-torque regressor with friction columns and the standard
  parameter vector of a Robot.
- :mod:`.base_parameters`: Gautier's numerical base parameters (QR with column pivoting).
- :mod:`.excitation`: Swevers' finite Fourier series, optimised for cond(Y_base).
- :mod:`.measurements`: /joint_states from a bag, filtered, differentiated, decimated.
- :mod:`.estimation`: ordinary and iterated weighted least squares with covariance.
- :mod:`.consistency`: pseudo-inertia check of standard parameters.
"""
