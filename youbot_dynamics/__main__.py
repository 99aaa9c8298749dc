"""`python -m youbot_dynamics`: the youbot-dynamics command line."""
import sys

from youbot_dynamics.cli import main

sys.exit(main())
