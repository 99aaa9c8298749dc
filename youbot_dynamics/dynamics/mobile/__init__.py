"""dynamics/mobile/: the youBot's omnidirectional base as pure functions: mecanum kinematics
(mecanum.py), wheel odometry on SE(2) (odometry.py), the wheel-floor contact pieces (normal
loads, roller friction: wheel_floor.py), the PI wheel-speed controller
(base_controller.py) and twist commands reached within acceleration limits (ramp.py)."""
