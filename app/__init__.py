"""GyroLab: teaching-lab software for fibre-optic-gyro north finding."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("gyrolab")
except PackageNotFoundError:  # running from a source tree without installing
    __version__ = "0.0.0+source"
