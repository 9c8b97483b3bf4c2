"""transfertwin: digital twins of object-transfer systems."""

from transfertwin._errors import InputError

__all__ = ["InputError", "__version__"]
__version__ = "0.1.0"
