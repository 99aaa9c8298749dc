"""systems/: classic test systems written as equations (squeezer, woodpecker, ...)."""
