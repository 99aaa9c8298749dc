"""dynamics/: rigid-body algorithms over Pinocchio, joint friction, contact, constraints."""
