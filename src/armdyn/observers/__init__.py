"""Sensing contact without a sensor: momentum observers, detection, isolation and contact estimation."""
