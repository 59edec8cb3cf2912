"""motion2video: human motion in, video out."""

__version__ = "0.1.0"
