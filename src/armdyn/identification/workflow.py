"""From a robot's log to a model that predicts it: preprocessing, the friction law, least squares on
the base parameters, the physically consistent estimate, and validation on held-out samples.

tau = W(q, qd, qdd) phi (Lewis, Dawson and Abdallah 2004, Table 3.3.1, property 9) with W's columns
extended by the friction law (``armdyn.identification.friction``), the reflected motor inertias and a
torque offset per joint (the bias of a joint-torque sensor or of a current measurement). The steps
follow the usual practice of the field (Swevers, Verdonck and De Schutter, "Dynamic model
identification for industrial robots", IEEE Control Systems 27(5), 2007; Gautier, "Dynamic
identification of robots with power model", ICRA 1997):

1. the log is resampled on a uniform grid, its positions low-passed without phase shift and
   differentiated, the torques filtered by the same filter, the samples decimated
   (``armdyn.identification.preprocess``);
2. the friction law's nonlinear parameters are fitted by variable projection;
3. ordinary least squares on the base parameters, with standard errors per joint;
4. the physically consistent estimate of every link's ten parameters, each pseudo-inertia positive
   semidefinite, regularized toward the prior model (``armdyn.identification.consistent``);
5. the identified arm: a Robot with the estimated links and the fitted friction, so that
   ``arm.inverse_dynamics`` and ``simulate`` use the very law that was fitted.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from armdyn.dynamics.regressor import BODY_PARAMETERS, BaseParameters, base_parameters, parameters, regressor
from armdyn.errors import ModelError
from armdyn.identification.friction import LAWS, FrictionLaw, fit_nonlinear
from armdyn.identification.least_squares import MAX_CONDITION
from armdyn.identification.log import Log
from armdyn.identification.preprocess import Prepared, prepare
from armdyn.model import ArmModel, Inertial

Progress = Callable[[str], None]


@dataclass(frozen=True)
class Columns:
    """Which columns of the extended regressor a model holds, and their names.

    The full parameter vector is [the 10 n rigid-body parameters | per joint: the friction law's
    linear parameters, then Ia if motor inertias are estimated, then the offset if any].

    Parameters
    ----------
    n : int
        The number of joints.
    law : FrictionLaw
        The friction law, with its nonlinear parameters.
    motor_inertia : bool
        Whether a reflected motor inertia Ia is a column of each joint.
    offset : bool
        Whether a torque offset is a column of each joint.
    """

    n: int
    law: FrictionLaw
    motor_inertia: bool
    offset: bool

    @property
    def per_joint(self) -> tuple[str, ...]:
        return self.law.linear_names + (("Ia",) if self.motor_inertia else ()) + (("offset",) if self.offset else ())

    @property
    def names(self) -> list[str]:
        rigid = [f"{name}{i + 1}" for i in range(self.n) for name in BODY_PARAMETERS]
        return rigid + [f"{name}{j + 1}" for j in range(self.n) for name in self.per_joint]

    def matrix(
        self, arm: ArmModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, friction: np.ndarray | None = None
    ) -> np.ndarray:
        """The extended regressor at the samples.

        Parameters
        ----------
        arm : ArmModel
            The arm whose rigid-body regressor (Table 3.3.1, property 9) is extended.
        q, qd, qdd : numpy.ndarray
            (N, n) states.
        friction : numpy.ndarray, optional
            (N, n, k_law): the friction law's columns, when computed elsewhere (filtered as the torques
            were); default the law at qd.

        Returns
        -------
        numpy.ndarray
            (N, n, 10 n + n k).
        """
        rigid = regressor(arm, q, qd, qdd)[..., : 10 * self.n]
        law = self.law.columns(qd) if friction is None else friction  # (N, n, k_law)
        extra = [law]
        if self.motor_inertia:
            extra.append(qdd[..., None])
        if self.offset:
            extra.append(np.ones(qd.shape + (1,)))
        per_joint = np.concatenate(extra, axis=-1)  # (N, n, k)
        k = per_joint.shape[-1]
        block = np.zeros(qd.shape + (self.n * k,))
        for j in range(self.n):
            block[..., j, j * k : (j + 1) * k] = per_joint[..., j, :]
        return np.concatenate([rigid, block], axis=-1)


@dataclass(frozen=True)
class Validation:
    """Predicted against measured torques, per joint.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times (N,).
    measured, predicted : numpy.ndarray
        (N, n) torques.
    joint_names : list of str
        The joints.
    """

    t: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    joint_names: list[str]

    @property
    def residual(self) -> np.ndarray:
        return self.measured - self.predicted

    @property
    def rms(self) -> np.ndarray:
        """Root mean square of measured minus predicted torque per joint (N m)."""
        return np.sqrt(np.mean(self.residual**2, axis=0))

    @property
    def normalized_rms(self) -> np.ndarray:
        """rms over the root mean square of the measured torque, per joint (1 is a model predicting 0)."""
        return self.rms / np.sqrt(np.mean(self.measured**2, axis=0))

    def table(self) -> object:
        """Per joint: rms (N m), normalized rms and the measured torque's rms.

        Returns
        -------
        pandas.DataFrame
            One row per joint.
        """
        import pandas as pd

        return pd.DataFrame(
            {
                "rms (N m)": self.rms,
                "normalized rms": self.normalized_rms,
                "measured rms (N m)": np.sqrt(np.mean(self.measured**2, axis=0)),
            },
            index=pd.Index(self.joint_names, name="joint"),
        )


@dataclass(frozen=True)
class IdentifiedModel:
    """An arm identified from a log: estimates, their quality and the arm that predicts the log.

    Made by ``identify_log``. ``predict`` uses the extended regressor with ``phi`` (the consistent
    estimate where one was made, else the least-squares one through the base parameters);
    ``arm`` is a Robot built from the consistent estimate (None without it).

    Parameters
    ----------
    prior : ArmModel
        The arm given: its structure, and the prior of the consistent estimate.
    columns : Columns
        The extended regressor's columns (friction law included).
    base : BaseParameters
        The rigid-body and motor base parameters.
    keep : numpy.ndarray
        The indices, into the full parameter vector, of the columns least squares estimated
        (base rigid-body columns, then every friction, motor and offset column).
    regrouping : numpy.ndarray
        (r, P): the estimated combinations of the full parameters.
    phi_least_squares, standard_errors : numpy.ndarray
        The least-squares estimate of those combinations and its standard errors, (r,).
    names : list of str
        The combinations' names.
    condition_number : float
        Of the stacked regressor least squares used.
    phi : numpy.ndarray
        The full parameter vector (P,), consistent where ``consistent`` is not None.
    consistent : object or None
        The ConsistentEstimate, or None.
    arm : ArmModel or None
        The identified arm.
    prepared : Prepared
        The preprocessed training samples.
    timings : dict
        Seconds per step.
    """

    prior: ArmModel
    columns: Columns
    base: BaseParameters
    keep: np.ndarray
    regrouping: np.ndarray
    phi_least_squares: np.ndarray
    standard_errors: np.ndarray
    names: list[str]
    condition_number: float
    phi: np.ndarray
    consistent: object | None
    arm: ArmModel | None
    prepared: Prepared
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def law(self) -> FrictionLaw:
        return self.columns.law

    @property
    def offsets(self) -> np.ndarray:
        """Each joint's torque offset (N m), zeros when none was estimated."""
        if not self.columns.offset:
            return np.zeros(self.columns.n)
        k = len(self.columns.per_joint)
        return self.phi[10 * self.columns.n + k - 1 :: k].copy()

    @property
    def relative_standard_errors(self) -> np.ndarray:
        """Standard error over |estimate| of each least-squares combination (inf where the estimate is 0)."""
        with np.errstate(divide="ignore"):
            return self.standard_errors / np.abs(self.phi_least_squares)

    def predict(self, q: object, qd: object, qdd: object) -> np.ndarray:
        """The torques the identified model predicts (offsets included).

        Parameters
        ----------
        q, qd, qdd : array_like
            States, (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n) torques.
        """
        q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
        return self.columns.matrix(self.prior, q, qd, qdd) @ self.phi

    def validate(self, log: Log, gains: object = None) -> Validation:
        """Predicted against measured torque at the log's own samples (see ``validate``).

        Parameters
        ----------
        log : Log
            Held-out measurements.
        gains : array_like, optional
            For a log of motor currents.

        Returns
        -------
        Validation
        """
        if log.joint_names is None:
            import dataclasses

            log = dataclasses.replace(log, joint_names=tuple(self.prior.joint_names))
        return validate(self.predict, log, self.prepared, gains)

    def parameter_table(self) -> object:
        """A pandas DataFrame: each least-squares combination, its estimate, standard error, relative
        standard deviation (%) and, with a consistent estimate, the consistent value.

        Returns
        -------
        pandas.DataFrame
            One row per estimated combination.
        """
        import pandas as pd

        frame = pd.DataFrame(
            {
                "estimate": self.phi_least_squares,
                "std. error": self.standard_errors,
                "rel. std. (%)": 100 * self.relative_standard_errors,
            },
            index=pd.Index(self.names, name="parameter"),
        )
        if self.consistent is not None:
            frame["consistent"] = self.regrouping @ self.phi
        return frame


def _torques(log: Log, gains: object) -> Log:
    """The log with joint torques: measured ones, or motor currents times the current-to-torque gains."""
    import dataclasses

    if log.tau is not None:
        if gains is not None:
            raise ModelError(f"{log.source}: the log holds torques; gains go with a log of motor currents")
        return log
    if gains is None:
        raise ModelError(
            f"{log.source}: the log holds motor currents, not torques: give the current-to-torque gains per joint "
            "(gains=..., N m/A, gear included; armdyn.identification.gains estimates them from a payload run)"
        )
    g = np.asarray(gains, dtype=float)
    if g.shape != (log.n,) or not np.all(np.isfinite(g)) or np.any(g == 0):
        raise ModelError(f"gains must be {log.n} finite non-zero numbers (N m/A), one per joint; got {gains!r}")
    assert log.current is not None
    return dataclasses.replace(log, tau=log.current * g, current=None)


def _least_squares(
    X: np.ndarray, y: np.ndarray, n: int, lags: int, nonlinear: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """phi, its standard errors and the condition number of the column-scaled X, by QR.

    ``nonlinear`` (rows, m) is the residual's Jacobian with respect to parameters fitted before and held
    here (the friction law's nonlinear ones): the covariance is then that of all of them together
    (Golub and Pereyra 1973), so that the standard errors of phi count their uncertainty too.

    The samples of a filtered log are correlated in time (the filter spreads each sample's noise over its
    neighbours), and the joints of one sample share it: the covariance is Newey and West's ("A simple,
    positive semi-definite, heteroskedasticity and autocorrelation consistent covariance matrix",
    Econometrica 55(3), 1987), (X^T X)^-1 S (X^T X)^-1 with S the Bartlett-weighted sum of the scores'
    autocovariances up to ``lags`` samples, a score being one sample's X^T e over its n joints.
    """
    from scipy.linalg import solve_triangular

    r = X.shape[1]
    scale = np.sqrt(np.sum(X**2, axis=0))
    scale[scale == 0] = 1.0
    Xs = X / scale  # column scaling: the condition number says what the data excite, not the units
    R: np.ndarray = np.linalg.qr(np.column_stack([Xs, y]), mode="r")  # type: ignore[assignment]
    singular = np.linalg.svd(R[:r, :r], compute_uv=False)
    condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")
    if condition > MAX_CONDITION:
        raise ModelError(
            f"the samples do not excite the {r} identifiable parameters: the scaled stacked regressor has condition "
            f"number {condition:.3g} (the limit is {MAX_CONDITION:.0e}); move every joint over a wide range with "
            "varied velocities and accelerations, or give a longer log"
        )
    phi = solve_triangular(R[:r, :r], R[:r, r])
    residual = y - Xs @ phi
    if nonlinear is not None and nonlinear.shape[1]:
        width = np.sqrt(np.sum(nonlinear**2, axis=0))
        width[width == 0] = 1.0
        Xs = np.column_stack([Xs, nonlinear / width])
        R = np.linalg.qr(Xs, mode="r")  # type: ignore[assignment]
    total = Xs.shape[1]
    scores = (Xs * residual[:, None]).reshape(-1, n, total).sum(axis=1)  # (N, total)
    samples = scores.shape[0]
    middle = scores.T @ scores
    for lag in range(1, min(lags, samples - 1) + 1):
        shared = scores[lag:].T @ scores[:-lag]
        middle += (1 - lag / (lags + 1)) * (shared + shared.T)
    # the degrees of freedom the fit used, counted in effectively independent rows (the residuals' own
    # long-run variance ratio, Bartlett-weighted as S is)
    errors_by_sample = residual.reshape(-1, n)
    power = float(np.sum(errors_by_sample**2)) or 1.0
    ratio = 1.0 + 2.0 * sum(
        (1 - lag / (lags + 1)) * float(np.sum(errors_by_sample[lag:] * errors_by_sample[:-lag])) / power
        for lag in range(1, min(lags, samples - 1) + 1)
    )
    effective = residual.size / max(ratio, 1.0)
    middle *= effective / max(effective - total, 1.0)
    inverse = solve_triangular(R[:total, :total], np.eye(total))  # (X^T X)^-1 = R^-1 R^-T
    covariance = inverse @ (inverse.T @ middle @ inverse) @ inverse.T
    errors = np.sqrt(np.maximum(np.diag(covariance)[:r], 0.0))
    return phi / scale, errors / scale, condition


def _stacked(columns: Columns, arm: ArmModel, prepared: Prepared) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The extended regressor and torques of every sample stacked: X (N n, P), y (N n,), joint (N n,).

    The friction law's columns, which are not smooth in the states, go through the filter the torques went
    through (parallel filtering, Gautier 1997); the rigid-body columns are smooth within the cut-off.
    """
    friction = None
    if prepared.untrimmed is not None:
        friction = prepared.filtered_as_torques(columns.law.columns(prepared.untrimmed[1]))
    X = columns.matrix(arm, prepared.q, prepared.qd, prepared.qdd, friction)
    assert prepared.tau is not None
    return X.reshape(-1, X.shape[-1]), prepared.tau.reshape(-1), np.tile(np.arange(arm.n), len(prepared.q))


def _nonlinear_jacobian(columns: Columns, keep: np.ndarray, phi: np.ndarray, prepared: Prepared) -> np.ndarray | None:
    """d(prediction)/d(the law's nonlinear parameters) at each row (N n, n k'), filtered as the torques were:
    each joint's amplitude (A or Fs) times its nonlinear term's derivatives; None for a law without any."""
    from armdyn.identification.friction import nonlinear_derivatives

    law, n = columns.law, columns.n
    if not law.nonlinear_names:
        return None
    k = len(columns.per_joint)
    amplitude_index = 10 * n + np.arange(n) * k + len(law.linear_names) - 1  # A or Fs: the law's last linear one
    full = np.zeros(10 * n + n * k)
    full[keep] = phi
    amplitude = full[amplitude_index]
    if prepared.untrimmed is not None:
        slopes = prepared.filtered_as_torques(nonlinear_derivatives(law.name, prepared.untrimmed[1], law.nonlinear))
    else:
        slopes = nonlinear_derivatives(law.name, prepared.qd, law.nonlinear)
    samples, _, m = slopes.shape
    weighted = slopes * amplitude[None, :, None]
    spread = weighted[:, :, None, :] * np.eye(n)[None, :, :, None]
    return spread.reshape(samples * n, n * m)


def _base_selection(columns: Columns, base: BaseParameters) -> tuple[np.ndarray, np.ndarray]:
    """Indices into the full vector of the columns least squares estimates, and the regrouping (r, P).

    The rigid-body columns are the base ones (Gautier 1991), the motor inertia of a joint whose
    column is a rigid-body one's (the first joint's Ia beside its Izz) regrouped with it; every
    friction and offset column is its own parameter.
    """
    n, k = columns.n, len(columns.per_joint)
    total = 10 * n + n * k
    ia = columns.per_joint.index("Ia") if columns.motor_inertia else -1
    to_full = {i: i for i in range(10 * n)}  # base_parameters' 14 n index -> full index
    for j in range(n):
        if ia >= 0:
            to_full[10 * n + 4 * j + 3] = 10 * n + j * k + ia
    kept_rigid, rows = [], []
    for row, column in zip(base.regrouping, base.columns.tolist(), strict=True):
        if column not in to_full:  # a friction column of base_parameters: the law's own columns replace them
            continue
        full_row = np.zeros(total)
        for index in np.flatnonzero(row).tolist():
            if index in to_full:
                full_row[to_full[index]] = row[index]
        kept_rigid.append(to_full[column])
        rows.append(full_row)
    others = [10 * n + j * k + c for j in range(n) for c in range(k) if c != ia]
    for other in others:
        full_row = np.zeros(total)
        full_row[other] = 1.0
        rows.append(full_row)
    return np.array(kept_rigid + others), np.array(rows)


def identified_arm(prior: ArmModel, columns: Columns, phi: np.ndarray, name: str | None = None) -> ArmModel:
    """The arm of a full parameter vector: the prior's kinematics and limits, the estimated links, friction
    (joint side, gear 1) and motor inertias. Offsets are not the arm's (they are the sensor's).

    Parameters
    ----------
    prior : ArmModel
        The arm whose kinematics, limits and names are kept.
    columns : Columns
        The columns of ``phi``.
    phi : numpy.ndarray
        The full parameter vector, physically consistent.
    name : str, optional
        The new arm's name (default the prior's with "_identified").

    Returns
    -------
    ArmModel
        The identified arm, of the prior's class.
    """
    import dataclasses

    n, k = columns.n, len(columns.per_joint)
    per_joint = phi[10 * n :].reshape(n, k)
    linear = per_joint[:, : len(columns.law.linear_names)]
    friction = columns.law.link_fields(linear)
    links = []
    for i, link in enumerate(prior.links):
        fields: dict[str, Any] = {"coulomb": (0.0, 0.0), **friction[i], "gear_ratio": 1.0}
        jm = per_joint[i, columns.per_joint.index("Ia")] if columns.motor_inertia else 0.0
        fields["motor_inertia"] = float(max(jm, 0.0))
        body = phi[10 * i : 10 * i + 10].copy()
        body[0] = max(body[0], 0.0)  # a consistent estimate's mass is >= 0 up to the solver's tolerance
        inertial = Inertial.from_parameters(body, link.name, strict=False)
        links.append(dataclasses.replace(link, inertial=inertial, **fields))
    return prior.replace(links, name=name or f"{prior.name}_identified")


def identify_log(
    arm: ArmModel,
    log: Log,
    *,
    friction: str = "sigmoid",
    consistent: bool = True,
    holdout: float = 0.0,
    gains: Sequence[float] | np.ndarray | None = None,
    cutoff: float | None = None,
    decimate: int | None = None,
    trim: float | None = None,
    motor_inertia: bool = True,
    offset: bool = True,
    regularization: float = 1e-4,
    mass_tolerance: float | None = None,
    progress: Progress | None = None,
) -> IdentifiedModel:
    """Identify an arm from a log of measured positions and torques (or motor currents).

    Parameters
    ----------
    arm : ArmModel
        The arm's structure (kinematics), and the prior of the consistent estimate (its URDF or
        catalogue values).
    log : Log
        The measurements (``armdyn.identification.log``): time, q, optionally qd, and tau or current.
    friction : str, optional
        The friction law per joint, one of "viscous", "coulomb", "stribeck", "sigmoid" (default).
    consistent : bool, optional
        Also estimate every link's ten parameters with its pseudo-inertia positive semidefinite
        (default True); the identified arm is built from that estimate.
    holdout : float, optional
        The share of the log, at its end, kept out of the estimate (0 to 0.9; default 0: all used).
        ``validate`` predicts it.
    gains : array_like, optional
        Current-to-torque gains per joint (N m/A), for a log of motor currents.
    cutoff, decimate, trim
        Preprocessing (``armdyn.identification.preprocess.prepare``): the low-pass cut-off (Hz,
        default from the excitation's bandwidth), the decimation factor and the seconds trimmed
        at each end.
    motor_inertia, offset : bool, optional
        Estimate a reflected motor inertia and a torque offset per joint (both default True; the
        Coulomb and Stribeck laws hold an offset in their asymmetric Coulomb terms already, so
        with them ``offset`` is not estimated apart).
    regularization : float, optional
        Weight of the distance to the prior in the consistent estimate (default 1e-4, relative to
        the data term): it settles the parameters the data cannot tell apart.
    mass_tolerance : float, optional
        Bound each link's mass within this share of the prior's (e.g. 0.1: within 10%); default none.
    progress : callable, optional
        Called with a line of text before each long step.

    Returns
    -------
    IdentifiedModel

    Raises
    ------
    armdyn.ModelError
        When the log does not fit the arm (joints, units), holds currents without gains, does not
        excite the identifiable parameters, or the consistent estimate is infeasible with the bounds.
    """
    say = progress or (lambda text: None)
    if friction not in LAWS:
        raise ModelError(f"friction must be one of {', '.join(LAWS)}, got {friction!r}")
    if not (isinstance(holdout, (int, float)) and 0.0 <= holdout <= 0.9):
        raise ModelError(f"holdout must be a share of the log between 0 and 0.9, got {holdout!r}")
    log.check_arm(arm)
    log = _torques(log, gains)
    train = log.split(1.0 - holdout)[0] if holdout > 0 else log
    timings: dict[str, float] = {}
    start = time.perf_counter()
    say(f"preprocessing {train.samples} samples")
    prepared = prepare(train, cutoff=cutoff, decimate=decimate, trim=trim)
    timings["preprocess"] = time.perf_counter() - start

    start = time.perf_counter()
    say(f"fitting the {friction} friction law")
    base = base_parameters(arm, drives=motor_inertia)  # the rigid-body base set, with Ia where estimated
    n = arm.n
    offset = offset and friction not in ("coulomb", "stribeck")  # an asymmetric Coulomb law holds the offset already
    law = FrictionLaw(friction, np.zeros((n, 0)))
    if law.nonlinear_names:
        linear_part = FrictionLaw({"stribeck": "coulomb", "sigmoid": "viscous"}[friction], np.zeros((n, 0)))
        fixed = Columns(n, linear_part, motor_inertia, offset)
        X, y, _ = _stacked(fixed, arm, prepared)
        keep, _ = _base_selection(fixed, base)
        velocities, through = prepared.qd, None
        if prepared.untrimmed is not None:
            velocities, through = prepared.untrimmed[1], prepared.filtered_as_torques
        law = fit_nonlinear(friction, X[:, keep], y, velocities, through)
    columns = Columns(n, law, motor_inertia, offset)
    X, y, _ = _stacked(columns, arm, prepared)
    keep, regrouping = _base_selection(columns, base)
    timings["friction"] = time.perf_counter() - start

    start = time.perf_counter()
    say("least squares on the base parameters")
    lags = max(1, int(np.ceil(2 * prepared.rate / prepared.cutoff)))  # the filter's memory, in samples
    phi_ls, _, _ = _least_squares(X[:, keep], y, n, lags)
    sensitivity = _nonlinear_jacobian(columns, keep, phi_ls, prepared)
    phi_ls, errors, condition = _least_squares(X[:, keep], y, n, lags, sensitivity)
    timings["least_squares"] = time.perf_counter() - start
    full_names = columns.names
    names = [_combination(row, full_names) for row in regrouping]
    phi = np.zeros(X.shape[1])
    phi[keep] = phi_ls  # the least-squares model: each kept column carries its combination
    estimate = None
    identified = None
    if consistent:
        from armdyn.identification.consistent import bounds_from_prior, consistent_estimate

        start = time.perf_counter()
        say("the physically consistent estimate (semidefinite program)")
        k = len(columns.per_joint)
        prior = np.zeros(X.shape[1])
        prior[: 10 * n] = parameters(arm)[: 10 * n]
        prior[10 * n :] = phi[10 * n :]
        lower = np.tile(np.concatenate([law.lower_bounds(), [0.0] * motor_inertia, [-np.inf] * offset]), n)
        upper = np.tile(np.concatenate([law.upper_bounds(), [np.inf] * motor_inertia, [np.inf] * offset]), n)
        mass_bounds = bounds_from_prior(prior[: 10 * n], n, mass_tolerance) if mass_tolerance is not None else None
        estimate = consistent_estimate(
            X,
            y,
            n,
            prior=prior,
            regularization=regularization,
            mass_bounds=mass_bounds,
            extra_bounds=np.column_stack([lower, upper]) if k else None,
        )
        phi = np.asarray(estimate.phi, dtype=float)
        identified = identified_arm(arm, columns, phi)
        timings["consistent"] = time.perf_counter() - start
    return IdentifiedModel(
        arm, columns, base, keep, regrouping, phi_ls, errors, names, condition, phi, estimate, identified, prepared,
        timings,
    )  # fmt: skip


def _combination(row: np.ndarray, names: list[str]) -> str:
    terms = []
    for index in np.flatnonzero(np.abs(row) > 1e-12):
        c = row[index]
        terms.append(names[index] if abs(c - 1) < 1e-9 else f"{c:.6g}*{names[index]}")
    return " + ".join(terms).replace("+ -", "- ")


def validate(predict: Callable[..., np.ndarray], log: Log, prepared: Prepared, gains: object = None) -> Validation:
    """Predicted against measured torque at a log's own sample times.

    The log is preprocessed as the training samples were (the same cut-off, no decimation); the
    predicted torque at the filtered states is interpolated back onto the log's own times, and
    compared with the torque measured there (unfiltered), away from the trimmed ends.

    Parameters
    ----------
    predict : callable
        predict(q, qd, qdd) -> tau for (N, n) states: ``IdentifiedModel.predict``, or a reference
        arm's ``inverse_dynamics``.
    log : Log
        The held-out measurements.
    prepared : Prepared
        The training samples' preprocessing, whose cut-off and trim are used.
    gains : array_like, optional
        For a log of motor currents.

    Returns
    -------
    Validation
    """
    log = _torques(log, gains)
    held = prepare(log, cutoff=prepared.cutoff, decimate=1, trim=prepared.trim)
    predicted = np.asarray(predict(held.q, held.qd, held.qdd), dtype=float)
    inside = (log.t >= held.t[0]) & (log.t <= held.t[-1])
    at_samples = np.column_stack([np.interp(log.t[inside], held.t, predicted[:, j]) for j in range(log.n)])
    assert log.tau is not None
    names = list(log.joint_names) if log.joint_names else [f"joint{j + 1}" for j in range(log.n)]
    return Validation(log.t[inside], log.tau[inside], at_samples, names)
