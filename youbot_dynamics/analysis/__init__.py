"""analysis/: work-precision sweeps, references, stability probes, plots."""
