"""Identification of an arm's parameters from measured motion and torques."""
