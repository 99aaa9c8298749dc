"""Test-wide settings, applied before any test module imports rclpy.

- ``ROS_PYTHON_CHECK_FIELDS=1``: every rclpy message built in a test process (and in the
  node processes the tests start, which inherit the environment) checks its field types,
  as a strict subscriber would; a wrong type raises instead of publishing garbage.
- Hypothesis profiles for the fuzz tests (test/*/test_fuzz_*.py): ``ci`` (default; bounded,
  derandomised, no example database written) and ``thorough`` (many more random
  examples): ``HYPOTHESIS_PROFILE=thorough pytest test/*/test_fuzz_*.py``.
"""
from __future__ import annotations

import os

os.environ["ROS_PYTHON_CHECK_FIELDS"] = "1"

from hypothesis import HealthCheck, settings  # noqa: E402

FUZZ_EXAMPLES = {"ci": 40, "thorough": 2000}
"""Examples per fuzz test in each profile."""

for _name, _examples in FUZZ_EXAMPLES.items():
    settings.register_profile(_name, max_examples=_examples, deadline=None, database=None,
                              derandomize=_name == "ci", print_blob=True,
                              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                                     HealthCheck.function_scoped_fixture])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
