"""Identification of an arm's dynamic parameters from a robot's log."""
