"""Observers: the generalized-momentum observer, collision detection, isolation and contact forces."""
