"""sim/: state, integrators with statistics, events, scenes, the simulator loop."""
