"""Parameter set and controller gains of the simulated hexacopter.

The aircraft is a planar PNPNPN hexacopter of the 2-3 kg class of the paper (Dutta et al., Fig. 1): the arm is
half the hub-to-hub distance 0.6096 m that the paper uses as the Dryden span. The shipped design has bidirectional
rotors and no rotor drag or weathervane moment, so that after a rotor failure it holds heading and flies in a
regime where its dynamics are close to linear, as the paper's aircraft does; :data:`REGULAR_HEXACOPTER` is the
regular aircraft with one-way rotors (``docs/results.md`` compares the two). Each value carries its source or
reason in the field's comment; the constants are typical of 10-inch propellers on ~700 kV motors
(thrust and torque coefficients as in the UIUC propeller database for 10x4.5 propellers, rotor drag and
flapping coefficients of the order identified by Martin & Salaun (2010) and Mahony, Kumar & Corke (2012)
scaled to this size).

References
----------
.. [1] R. Mahony, V. Kumar, P. Corke, "Multirotor Aerial Vehicles: Modeling, Estimation, and Control of
       Quadrotor", IEEE Robotics & Automation Magazine 19(3), 2012 (rotor drag, blade flapping).
.. [2] P. Martin, E. Salaun, "The true role of accelerometer feedback in quadrotor control", ICRA 2010.
.. [3] J. B. Brandt, M. S. Selig, "Propeller performance data at low Reynolds numbers", AIAA 2011-1255
       (UIUC propeller data base: C_T ~ 0.11, C_P ~ 0.045 for 10-inch APC propellers).
"""

from __future__ import annotations

import numbers
from dataclasses import asdict, dataclass, fields, replace

import numpy as np

__all__ = ["HexacopterParameters", "ControllerGains", "REGULAR_HEXACOPTER", "FleetSpread", "FLEET_SEED_KEY"]


@dataclass(frozen=True)
class HexacopterParameters:
    """Physical parameters (SI units) of the simulated hexacopter.

    Attributes
    ----------
    mass : float
        2.4 kg: a 550-650 mm class hexacopter with a 4S battery (the paper's aircraft is of this class).
    gravity : float
        9.80665 m/s^2.
    ixx, iyy, izz : float
        0.045, 0.045, 0.080 kg m^2: six 0.2 kg motor/propeller/ESC masses on 0.3048 m arms
        (6 x 0.2 x 0.3048^2 / 2 = 0.028 about x and y, twice that about z) plus the central body.
    arm : float
        0.3048 m: half of the hub-to-hub distance 0.6096 m (2 ft) given in the paper.
    rotor_height : float
        0.05 m: rotor plane above the centre of gravity (H-forces then make pitch and roll moments).
    k_thrust : float
        1.57e-5 N s^2: T = k_thrust Omega^2, so that the six rotors carry 2.4 kg at Omega = 500 rad/s
        (4800 rpm), consistent with C_T ~ 0.11 of a 10-inch propeller.
    k_torque : float
        2.5e-7 N m s^2: Q = k_torque Omega^2 (Q/T = 0.016 m, from C_P / C_T of the same propeller).
    motor_time_constant : float
        0.03 s: first-order lag of the rotor speed (brushless motor with a 10-inch propeller).
    k_inflow : float
        7.2e-4 N s/m: T increases by k_inflow Omega w_hub when the hub descends relative to the air
        (blade-element slope dT/dw ~ 0.36 N/(m/s) at hover); it gives heave and roll/pitch damping and makes
        vertical and angular gusts act on the aircraft.
    k_rotor_drag : float
        0 (shipped design): rotor H-force -k_rotor_drag Omega v_hub (in-plane air-relative hub velocity).
        1.2e-4 N s/m (0.36 N/(m/s) for the six rotors at hover) is the order reported for small multirotors and
        is the value of :data:`REGULAR_HEXACOPTER`. Off in the shipped design because, measured on the same
        design (``docs/results.md``, "The shipped aircraft and its alternatives"), it makes the post-failure
        roll / pitch / yaw-rate dynamics of rotors 2 and 6 (mirror images with the same spin) so alike that
        the paper's whiteness rule cannot tell them apart; the paper's aircraft could.
    k_flapping : float
        4e-6 N s: blade-flapping moment k_flapping Omega (-v_y, v_x) of a rotor whose disc tilts away from
        the relative wind (0.06 N m at 5 m/s for six rotors).
    drag_area : float
        0.04 m^2: C_D A of the central body, drag ``-rho C_D A |v| v / 2``.
    air_density : float
        1.225 kg/m^3 (ISA sea level).
    k_weathervane : float
        0 (shipped design): yaw moment ``k_weathervane |v_h| v_y`` of the body, legs and arms in sideslip
        (turns the nose into the relative wind). 8e-4 N s^2 (a side area of ~0.03 m^2 a few cm behind the
        centre of gravity) in :data:`REGULAR_HEXACOPTER`. Off in the shipped design: it is quadratic in the
        relative wind, and in severe gusts it makes the post-failure yaw dynamics visibly nonlinear
        (measured in ``docs/results.md``).
    omega_min, omega_max : float
        60 and 1100 rad/s: rotor speed limits (idle -- regular rotors only -- and full throttle: 19 N per
        rotor, a thrust-to-weight ratio of 4.8, a 10-inch propeller at 10,500 rpm on a 6S battery). After a
        failure four rotors carry the aircraft; with 900 rad/s (:data:`REGULAR_HEXACOPTER`, ratio 3.2) they
        reach full speed in severe gusts, and that clipping is the largest nonlinearity left in the
        post-failure dynamics (measured in ``docs/results.md``).
    reversible_rotors : bool
        True (shipped design): bidirectional motors (reversible "3D" speed controllers and symmetric
        propellers): speeds in ``[-omega_max, omega_max]``, thrust :math:`k_T \\Omega |\\Omega|` and torque
        :math:`k_Q \\Omega |\\Omega|` change sign with the speed (inflow, rotor drag and flapping scale with
        :math:`|\\Omega|`, a first-order simplification for the reversed rotor, which only runs slowly in the
        cases studied). A planar PNPNPN hexacopter with one rotor failed holds heading only with the opposite
        rotor at zero thrust (Du et al. 2015); a reversible rotor can go there, so after the failure the
        aircraft holds heading with a small, stationary yaw variance, as the paper's does (Figs. 6-7 and its
        yaw steady-state threshold of 3e-4 rad^2). False (:data:`REGULAR_HEXACOPTER`): a rotor turns one way
        only, between ``omega_min`` and ``omega_max``, and its thrust is never negative; the opposite rotor
        then switches on and off its idle floor in gusts and the heading slips in severe turbulence.
    cg_x, cg_y : float
        0 m (shipped design): offset of the centre of gravity from the hub centre, forward (x) and to the right
        (y) in body axes, e.g. an off-centre payload. The rotors then sit at ``(arm cos psi_i - cg_x,
        arm sin psi_i - cg_y, -rotor_height)`` from the centre of gravity, about which the body rotates; the
        inertia stays ``ixx, iyy, izz`` (the parallel-axis term ``mass * cg^2`` is 0.5 % of ``ixx`` at 1 cm
        and neglected) and the body drag acts at the centre of gravity. ``hypot(cg_x, cg_y)`` must be below
        ``arm / 2``. :class:`FleetSpread` draws them per record.
    """

    mass: float = 2.4
    gravity: float = 9.80665
    ixx: float = 0.045
    iyy: float = 0.045
    izz: float = 0.080
    arm: float = 0.3048
    rotor_height: float = 0.05
    k_thrust: float = 1.57e-5
    k_torque: float = 2.5e-7
    motor_time_constant: float = 0.03
    k_inflow: float = 7.2e-4
    k_rotor_drag: float = 0.0
    k_flapping: float = 4e-6
    drag_area: float = 0.04
    air_density: float = 1.225
    k_weathervane: float = 0.0
    omega_min: float = 60.0
    omega_max: float = 1100.0
    reversible_rotors: bool = True
    # appended after reversible_rotors: the kernels read the vector of to_array() by position
    cg_x: float = 0.0
    cg_y: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.reversible_rotors, (bool, np.bool_)):
            raise TypeError(f"reversible_rotors must be a bool, got {self.reversible_rotors!r}")
        for name in ("cg_x", "cg_y"):
            v = getattr(self, name)
            if not np.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
        for f in fields(self):
            if f.name in ("reversible_rotors", "cg_x", "cg_y"):
                continue
            v = getattr(self, f.name)
            if not np.isfinite(v) or (v < 0) or (v == 0 and f.name not in
                                                 {"rotor_height", "k_inflow", "k_rotor_drag", "k_flapping",
                                                  "drag_area", "k_weathervane", "omega_min"}):
                raise ValueError(f"{f.name} must be a finite positive number, got {v!r}")
        if self.omega_min >= self.omega_max:
            raise ValueError(f"omega_min must be < omega_max, got {self.omega_min} >= {self.omega_max}")
        if np.hypot(self.cg_x, self.cg_y) >= self.arm / 2:
            raise ValueError(f"cg_x, cg_y: the centre-of-gravity offset must be below arm / 2 = {self.arm / 2:g} m, "
                             f"got ({self.cg_x!r}, {self.cg_y!r})")

    def to_array(self) -> np.ndarray:
        return np.array([getattr(self, f.name) for f in fields(self)], dtype=float)

    def to_dict(self) -> dict:
        return asdict(self)


#: The regular hexacopter: unidirectional rotors with a 60 rad/s idle floor, 900 rad/s full speed
#: (thrust-to-weight 3.2), rotor drag and the weathervane moment. It was tsfdi's shipped design until its
#: post-failure dynamics were measured to be nonlinear (``docs/results.md``);
#: ``simulate_hexacopter(params=REGULAR_HEXACOPTER)`` simulates it.
REGULAR_HEXACOPTER = HexacopterParameters(reversible_rotors=False, omega_max=900.0, k_rotor_drag=1.2e-4,
                                          k_weathervane=8e-4)


@dataclass(frozen=True)
class ControllerGains:
    """Gains of the cascade controller (paper's Fig. 2), designed at hover by pole placement.

    The loops, from outside in: velocity (PI in north-east axes, tilt command limited to ``max_tilt`` and
    rotated into the heading frame) -> pitch/roll commands; altitude (PID) -> collective Omega_0; attitude
    (PID) -> Omega_R, Omega_P; heading (P on the wrapped heading error, yaw-rate command limited to
    ``max_yaw_rate``) -> yaw rate (PI, anti-windup) -> Omega_Y, limited to ``max_yaw_control`` times
    ``1 - (|roll error| + |pitch error|) / yaw_priority_error`` so that the yaw term never takes the rotor
    speed range the attitude loops need. Controls are in rotor-speed units (rad/s) as in the paper's eq. 2
    (deviations about the collective speed, mixed in thrust: see the mixer in :mod:`tsfdi.datasets.hexacopter`).

    Design values (effectiveness per rad/s of control at hover, from the default parameters): attitude
    0.32 rad/s^2 -> natural frequency 16 rad/s, damping 1.0 (about half the motor bandwidth 1/0.03 s);
    altitude 0.039 m/s^2 -> 3.1 rad/s, damping 0.69 (it was 2.0 rad/s: the thrust-linear mixer no longer adds
    the thrust of the squared roll/pitch deviations, so the altitude loop has to replace the failed rotor's
    thrust itself; at 2.0 rad/s severe gusts after a failure sank the aircraft by up to 4.6 m); velocity 0.08 rad of tilt per m/s -> 0.8 rad/s; yaw
    0.019 rad/s^2 plus the aerodynamic yaw damping 0.44 1/s -> yaw-rate bandwidth about 2.3 rad/s (PI zero
    at 0.8 rad/s); heading 0.3 rad/s. The attitude loop is stiff and the velocity and heading loops soft so
    that, after a rotor failure, the yaw and velocity loops do not take the authority the attitude loops
    need to keep the aircraft flying. The stiff attitude loop (it was 400 / 55, natural frequency 11 rad/s)
    keeps the roll and pitch errors small in severe turbulence, so the attitude-priority limit of the yaw
    term takes the yaw authority away less often, and that limit can act earlier (``yaw_priority_error``
    0.6 rad, it was 0.8: on 64 fresh seeds per failed rotor in severe turbulence 0.8 lost 4 of 192 aircraft
    with the stiffer loop, 0.6 none); ``max_yaw_control`` 450 rad/s
    (it was 350) covers the yaw term a failed aircraft needs in severe gusts (trim 100-200 rad/s) and the
    yaw-rate integrator (``ki_yaw_rate`` 80, it was 40) rebuilds it faster after such a limit. With these
    values and the thrust-linear mixer (see :mod:`tsfdi.datasets.hexacopter`) no record of the shipped
    design (240 x 60 s, severe turbulence included) is lost, and the heading is held after the failure
    in light and moderate turbulence; a single gain set serves every record and turbulence level.
    """

    k_velocity: float = 0.08        # rad per m/s
    ki_velocity: float = 0.02       # rad per m
    k_altitude: float = 250.0       # rad/s per m
    kd_altitude: float = 110.0      # rad/s per m/s
    ki_altitude: float = 80.0       # rad/s per m s
    k_attitude: float = 800.0       # rad/s per rad
    k_rate: float = 100.0           # rad/s per rad/s
    ki_attitude: float = 100.0      # rad/s per rad s
    k_heading: float = 0.3          # rad/s of yaw-rate command per rad of heading error
    k_yaw_rate: float = 100.0       # rad/s per rad/s
    max_tilt: float = 0.3           # rad
    max_yaw_rate: float = 1.0       # rad/s
    ki_yaw_rate: float = 80.0       # rad/s per rad
    max_yaw_control: float = 450.0  # rad/s
    yaw_priority_error: float = 0.6  # rad

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not np.isfinite(v) or v < 0:
                raise ValueError(f"{f.name} must be a finite non-negative number, got {v!r}")

    def to_array(self) -> np.ndarray:
        return np.array([getattr(self, f.name) for f in fields(self)], dtype=float)

    def to_dict(self) -> dict:
        return asdict(self)


#: Second entropy word of the generator of a record's fleet draw: ``numpy.random.default_rng([seed,
#: FLEET_SEED_KEY])`` with the record's ``seed``. The turbulence uses ``default_rng(seed)``, so the aircraft
#: drawn for a record is independent of its gusts, and the gusts are the same with and without a fleet.
FLEET_SEED_KEY = 0xF1EE7

#: Largest accepted spreads: relative ones (fractions of the nominal value) and the centre-of-gravity offset (m).
_FLEET_MAX = {"mass": 0.5, "cg_offset": 0.1, "motor_constant": 0.5, "inertia": 0.5}


@dataclass(frozen=True)
class FleetSpread:
    """Spreads of a fleet of aircraft of one type that differ slightly in weight and handling (payloads).

    Hansen et al. (tsfdi's paper 002) analyse aircraft "of the same type but with small differences in weight and
    handling due to payloads"; with ``fleet=FleetSpread()`` each record of :func:`~tsfdi.datasets.simulate_hexacopter`
    / :func:`~tsfdi.datasets.make_hexacopter_dataset` flies its own aircraft drawn around the nominal
    :class:`HexacopterParameters`. Every quantity is drawn **uniformly and independently** in the interval given
    below (so a drawn value never leaves it), with one call ``rng.uniform(-1, 1, 5)`` of
    ``rng = numpy.random.default_rng([seed, FLEET_SEED_KEY])`` (``seed``: the record's seed), in the order mass,
    cg_x, cg_y, motor_constant, inertia: a record's aircraft depends only on its seed, and a spread set to 0
    leaves that quantity nominal without changing the others.

    Attributes
    ----------
    mass : float
        0.05, relative: ``mass = nominal * (1 + mass * U)``, U uniform in [-1, 1] (2.28-2.52 kg for the nominal
        2.4 kg, a payload of up to +-120 g).
    cg_offset : float
        0.01 m, absolute: ``cg_x`` and ``cg_y`` (see :class:`HexacopterParameters`) are each the nominal offset
        plus ``cg_offset * U`` (a payload off the centre; 1 cm is 3 % of the arm).
    motor_constant : float
        0.03, relative: one factor ``1 + motor_constant * U`` multiplies ``k_thrust`` and ``k_torque`` of all six
        rotors (another propeller batch: the torque-to-thrust ratio, a property of the propeller shape, is kept).
    inertia : float
        0.05, relative: one factor ``1 + inertia * U`` multiplies ``ixx``, ``iyy`` and ``izz`` (payload and
        battery placement).

    Each spread must be a finite number >= 0, at most 0.5 for the relative ones and 0.1 m for ``cg_offset``;
    every record is trimmed for its own aircraft (:func:`~tsfdi.datasets.trim`) and flown with the one gain set
    (:class:`ControllerGains`). With the default spreads no record was lost in light, moderate or severe
    turbulence, healthy or with rotor 1, 2 or 6 failed (``tests/datasets/test_hexacopter.py``); much larger
    spreads may lose records (flagged in ``lost_control``).
    """

    mass: float = 0.05
    cg_offset: float = 0.01
    motor_constant: float = 0.03
    inertia: float = 0.05

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
                raise TypeError(f"{f.name} must be a real number, got {v!r} ({type(v).__name__})")
            hi = _FLEET_MAX[f.name]
            if not np.isfinite(v) or not 0.0 <= v <= hi:
                raise ValueError(f"{f.name} must be a finite number in [0, {hi:g}], got {v!r}")
            object.__setattr__(self, f.name, float(v))

    def draw(self, params: HexacopterParameters, seed: int) -> tuple[HexacopterParameters, dict]:
        """The aircraft of the record with seed ``seed``: ``(parameters, values)``.

        ``values`` holds ``mass`` (kg), ``cg_x`` and ``cg_y`` (m), and the factors ``motor_constant`` and
        ``inertia`` (1: nominal), the record coordinates of the simulated dataset.
        """
        u = np.random.default_rng([int(seed), FLEET_SEED_KEY]).uniform(-1.0, 1.0, 5)
        kmot = 1.0 + self.motor_constant * u[3]
        kin = 1.0 + self.inertia * u[4]
        values = {"mass": params.mass * (1.0 + self.mass * u[0]),
                  "cg_x": params.cg_x + self.cg_offset * u[1], "cg_y": params.cg_y + self.cg_offset * u[2],
                  "motor_constant": kmot, "inertia": kin}
        drawn = replace(params, mass=values["mass"], cg_x=values["cg_x"], cg_y=values["cg_y"],
                        k_thrust=params.k_thrust * kmot, k_torque=params.k_torque * kmot,
                        ixx=params.ixx * kin, iyy=params.iyy * kin, izz=params.izz * kin)
        return drawn, values

    @classmethod
    def from_spec(cls, spec: str) -> FleetSpread:
        """``"default"`` or comma-separated ``name=value`` spreads (the others default), e.g.
        ``"mass=0.1,cg_offset=0.02"``: the ``--fleet`` option of ``tsfdi simulate``."""
        if not isinstance(spec, str):
            raise TypeError(f"fleet must be a string, got {type(spec).__name__}")
        names = [f.name for f in fields(cls)]
        kw = {}
        for item in (t.strip() for t in spec.split(",")):
            if item.lower() == "default":
                continue
            name, eq, value = item.partition("=")
            name = name.strip().replace("-", "_")
            if not eq or name not in names:
                raise ValueError(f"fleet: expected 'default' or name=value with a name in {', '.join(names)}, "
                                 f"got {item!r}")
            try:
                kw[name] = float(value)
            except ValueError:
                raise ValueError(f"{name} must be a number, got {value.strip()!r}") from None
        return cls(**kw)

    def to_dict(self) -> dict:
        return asdict(self)
