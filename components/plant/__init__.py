"""RobotPlant numerics: geared DC motors, traction, rigid body, encoders and odometry.

Pure numerics (no FMI import); the pythonfmu slave lives in :mod:`.fmu` and is not imported
here, so the cores can be used and tested without pythonfmu.
"""

from .dynamics import STATE_NAMES, plant_rates
from .encoder import WheelEncoder
from .kinematics import body_velocity, turn_radius
from .motor import MotorConstants, motor_constants_from_datasheet, steady_wheel_speed
from .odometry import EncoderOdometry
from .parameters import PlantParameters
from .plant import RobotPlantCore
from .traction import slip_ratio, traction_force

__all__ = [
    "STATE_NAMES", "plant_rates", "WheelEncoder", "body_velocity", "turn_radius",
    "MotorConstants", "motor_constants_from_datasheet", "steady_wheel_speed",
    "EncoderOdometry", "PlantParameters", "RobotPlantCore", "slip_ratio", "traction_force",
]
