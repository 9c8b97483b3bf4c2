"""transfertwin: digital twins of object-transfer systems."""

import os as _os

# Offscreen rendering without a display: EGL (falls back to what the user sets).
if "MUJOCO_GL" not in _os.environ and not _os.environ.get("DISPLAY"):
    _os.environ["MUJOCO_GL"] = "egl"

from transfertwin._errors import InputError

__all__ = ["InputError", "__version__"]
__version__ = "0.1.0"
