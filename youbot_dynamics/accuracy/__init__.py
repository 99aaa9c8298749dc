"""What a run is worth: work-precision sweeps against a reference, contact at its extremes,
uncertain scene parameters, and the Dask layer that runs independent cases."""
