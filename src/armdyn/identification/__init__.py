"""Identification from a robot's log: logs, preprocessing, friction laws, estimators, drive gains, payload."""
