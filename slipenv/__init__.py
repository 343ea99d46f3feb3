"""slipenv: Gymnasium environments for slip-aware navigation and control of off-road vehicles.

Importing the package registers the environments with Gymnasium; PyBullet is imported only
when an environment is built, so force laws, estimators and log tools stay light.
"""

from slipenv.envs.registration import register_envs

__version__ = "0.1.0"

register_envs()
