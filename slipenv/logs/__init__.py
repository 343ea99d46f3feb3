"""Measured logs in the slipenv-log/1 format (``log-format.md``): read, write, import.

A log is a folder with ``meta.json`` (vehicle, terrain, notes, any extra keys) and
``signals.csv`` (time [s], cumulative encoder counts, optional IMU, commands, torques and a
ground-truth pose). ``read_log``/``write_log`` validate against the contract and raise
``LogFormatError`` naming the file, row and column; ``Log.from_arrays`` builds a log from a
simulated episode with the same checks. ``slipenv.logs.rosbag`` imports ROS 1/2 bags and
``slipenv.logs.real`` converts the real datasets (OptiOdom, BorealTC); a run of each and one
generated log ship in the package (``slipenv.logs.examples.path(name)``).
"""

from slipenv.logs.errors import LogFormatError
from slipenv.logs.io import read_log, write_log
from slipenv.logs.log import GT_COLUMNS, Log, ground_truth_mask, required_columns
from slipenv.logs.meta import FORMAT, VEHICLE_KINDS, LogMeta, validate_meta

__all__ = [
    "FORMAT",
    "GT_COLUMNS",
    "VEHICLE_KINDS",
    "Log",
    "LogFormatError",
    "LogMeta",
    "ground_truth_mask",
    "read_log",
    "required_columns",
    "validate_meta",
    "write_log",
]
