"""model/: URDF -> Robot (immutable), rotations, screw axes and product of exponentials."""
