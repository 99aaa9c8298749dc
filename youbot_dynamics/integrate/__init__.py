"""The integrator library: the Stepper protocol and drive(), the registry of methods (own
fixed-step loops, scipy.integrate, SUNDIALS), hybrid events, constrained mechanisms and
statistics. Knows nothing of scenes."""
