"""ruledrobot: robot motion planning on ruled surfaces."""

__version__ = "0.1.0"
