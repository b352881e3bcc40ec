"""Multimodal (audio + force/torque) contact detection for object placing."""

__version__ = '0.1.0'
