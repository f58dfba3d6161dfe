"""Robot models: kinematics (differential drive, omnidirectional) and virtual sensors."""

from swarmpath.robot.kinematics import DiffDrive, Omni, Pose, wrap_angle
from swarmpath.robot.sensors import (
    SENSOR_MODELS,
    SensorModel,
    SensorReading,
    get_sensor_model,
    read_sensors,
)

__all__ = [
    "SENSOR_MODELS",
    "DiffDrive",
    "Omni",
    "Pose",
    "SensorModel",
    "SensorReading",
    "get_sensor_model",
    "read_sensors",
    "wrap_angle",
]
