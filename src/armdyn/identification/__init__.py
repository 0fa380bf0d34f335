"""Identification: from a robot's log (measured positions and torques or motor currents) to a
physically consistent model that predicts it (Lewis, Dawson and Abdallah 2004, Table 3.3.1,
property 9: tau = W(q, qd, qdd) phi).

- ``least_squares``: ``identify``, least squares on the base parameters with standard errors;
- ``excitation``: exciting trajectories and the data the regressor explains.
"""

from armdyn.identification.least_squares import (
    FrictionMisfitWarning,
    Identification,
    PoorExcitationWarning,
    identify,
)

__all__ = ["FrictionMisfitWarning", "Identification", "PoorExcitationWarning", "identify"]
