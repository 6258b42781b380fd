"""Parameter set and controller gains of the simulated hexacopter.

The aircraft is a planar PNPNPN hexacopter of the 2-3 kg class of the paper (Dutta et al., Fig. 1): the arm is
half the hub-to-hub distance 0.6096 m that the paper uses as the Dryden span. The default
(``HexacopterParameters()``) is a regular aircraft: fixed-pitch two-blade 10-inch propellers whose loads come
from blade element theory with a dynamic uniform inflow (the lowest Peters-He mode, Pitt & Peters), one-way
rotors between an idle and a full speed, rotor drag and hub moments from the blade elements, the weathervane
moment of the body, and gains scheduled over the forward speed. :data:`BIDIRECTIONAL_HEXACOPTER` is tsfdi's
previous shipped aircraft (bidirectional rotors, lumped rotor coefficients, no rotor drag or weathervane),
kept for comparison only. Each value carries its source or reason in the field's comment.

References
----------
.. [1] R. Mahony, V. Kumar, P. Corke, "Multirotor Aerial Vehicles: Modeling, Estimation, and Control of
       Quadrotor", IEEE Robotics & Automation Magazine 19(3), 2012 (rotor drag, blade flapping).
.. [2] P. Martin, E. Salaun, "The true role of accelerometer feedback in quadrotor control", ICRA 2010.
.. [3] J. B. Brandt, M. S. Selig, "Propeller performance data at low Reynolds numbers", AIAA 2011-1255
       (UIUC propeller data base: C_T ~ 0.11, C_P ~ 0.045 for 10-inch APC propellers).
.. [4] J. G. Leishman, "Principles of Helicopter Aerodynamics", 2nd ed., Cambridge 2006, ch. 2-3 (momentum
       and blade element theory, linear twist, Glauert's forward-flight inflow) and ch. 10 (dynamic inflow).
.. [5] D. M. Pitt, D. A. Peters, "Theoretical prediction of dynamic-inflow derivatives", Vertica 5, 1981.
.. [6] M. Bangura, R. Mahony, "Nonlinear dynamic modeling for high performance control of a quadrotor",
       ACRA 2012 (blade element and momentum theory for small fixed-pitch rotors).
"""

from __future__ import annotations

import numbers
from dataclasses import asdict, dataclass, fields, replace

import numpy as np

__all__ = ["HexacopterParameters", "ControllerGains", "BIDIRECTIONAL_HEXACOPTER", "FleetSpread", "FLEET_SEED_KEY"]


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
        1.57e-5 N s^2: T = k_thrust Omega^2 of the lumped rotor (``blade_element=False``), so that the six
        rotors carry 2.4 kg at Omega = 500 rad/s (4800 rpm), consistent with C_T ~ 0.11 of a 10-inch
        propeller [3]. The blade-element rotor's geometry is chosen to give the same hover thrust
        (:meth:`blade_element_hover`); the blade-element aircraft uses k_thrust only for the first guess of
        its trim.
    k_torque : float
        2.5e-7 N m s^2: Q = k_torque Omega^2 of the lumped rotor (Q/T = 0.016 m, from C_P / C_T of the same
        propeller); matched by the blade-element rotor in hover through ``profile_drag``.
    motor_time_constant : float
        0.03 s: first-order lag of the rotor speed (brushless motor with a 10-inch propeller).
    k_inflow : float
        Lumped rotor only (0 by default; 7.2e-4 N s/m in :data:`BIDIRECTIONAL_HEXACOPTER`): T increases by
        k_inflow Omega w_hub when the hub descends relative to the air (blade-element slope dT/dw ~ 0.36
        N/(m/s) at hover). The blade-element rotor has this effect through its inflow.
    k_rotor_drag : float
        1.2e-4 N s/m: additional lumped in-plane rotor force ``-k_rotor_drag Omega v_hub`` (in-plane
        air-relative hub velocity). The blade-element rotor has its own H-force (profile and induced drag of the
        blades), but a rigid blade-element rotor underestimates the rotor drag measured on flexible small
        propellers (about 0.076 N/(m/s) for six rotors at hover against the ~0.36 N/(m/s) of the order reported
        by Mahony et al. [1] and Martin & Salaun [2]); this term adds the part from blade flexing, at the value
        of that order (0.06 N/(m/s) per rotor at hover). Kept on paper 003's published physical quantities
        only: with it the failed aircraft's post-failure heading variance, measured by
        ``docs/scripts/hexacopter_quantities.py`` while tuning, came out lower than with 0 (the heading is the one
        quantity one-way rotors cannot reach: see the module docstring).
    k_flapping : float
        0 (4e-6 N s in :data:`BIDIRECTIONAL_HEXACOPTER`): additional blade-flapping pitching moment
        ``k_flapping Omega (-v_y, v_x)`` of a rotor whose disc tilts away from the relative wind. The
        blade-element rotor has its own hub moments (rolling moment of the advancing blade and pitching moment
        of the longitudinal inflow gradient); this term is for flexible blades, 0 by default as above.
    drag_area : float
        0.04 m^2: C_D A of the central body, drag ``-rho C_D A |v| v / 2``.
    air_density : float
        1.225 kg/m^3 (ISA sea level).
    k_weathervane : float
        8e-4 N s^2 (0 in :data:`BIDIRECTIONAL_HEXACOPTER`): yaw moment ``k_weathervane |v_h| v_y`` of the body,
        legs and arms in sideslip (turns the nose into the relative wind): a side area of ~0.03 m^2 a few cm
        behind the centre of gravity.
    omega_min, omega_max : float
        60 and 1100 rad/s: rotor speed limits (idle -- one-way rotors only -- and full throttle: 19 N per
        rotor, a thrust-to-weight ratio of 4.8 at 2.4 kg and 3.4 with a 30 % payload: a 10-inch propeller at
        10,500 rpm on a 6S battery). After a failure four rotors carry the aircraft.
    reversible_rotors : bool
        False (default): a rotor turns one way only, between ``omega_min`` and ``omega_max`` (the mixer
        clips the commands, the first-order motor then never leaves that range). True
        (:data:`BIDIRECTIONAL_HEXACOPTER`, lumped rotor only): bidirectional motors (reversible "3D" speed
        controllers and symmetric propellers): speeds in ``[-omega_max, omega_max]``, thrust
        :math:`k_T \\Omega |\\Omega|` and torque :math:`k_Q \\Omega |\\Omega|` change sign with the speed. A
        planar PNPNPN hexacopter with one rotor failed holds heading only with the opposite rotor at zero
        thrust (Du et al. 2015); a reversible rotor can go there, a one-way rotor only to its idle speed.
    cg_x, cg_y : float
        0 m (shipped design): offset of the centre of gravity from the hub centre, forward (x) and to the right
        (y) in body axes, e.g. an off-centre payload. The rotors then sit at ``(arm cos psi_i - cg_x,
        arm sin psi_i - cg_y, -rotor_height)`` from the centre of gravity, about which the body rotates; the
        inertia stays ``ixx, iyy, izz`` (the parallel-axis term ``mass * cg^2`` is 0.5 % of ``ixx`` at 1 cm
        and neglected) and the body drag acts at the centre of gravity. ``hypot(cg_x, cg_y)`` must be below
        ``arm / 2``. :class:`FleetSpread` draws them per record.
    blade_element : bool
        True (default): rotor loads from blade element theory with a dynamic uniform inflow (equations in
        :mod:`tsfdi.datasets.hexacopter`); False: the lumped coefficients ``k_thrust``, ``k_torque``,
        ``k_inflow``, ``k_rotor_drag`` and ``k_flapping`` (tsfdi's rotor until the blade-element one).
    blades : float
        2: blades per propeller (two-blade 10-inch propellers of this class [3]).
    rotor_radius : float
        0.127 m: a 10-inch propeller.
    chord : float
        0.02 m: blade chord (mean chord of 10-inch propellers: 15-25 mm); solidity ``blades chord / (pi R)``
        = 0.100.
    lift_slope : float
        5.7 1/rad: section lift-curve slope (0.9 of 2 pi for finite-thickness sections, Leishman [4] ch. 3).
    root_pitch, twist : float
        0.50 rad and -0.27 rad: blade pitch ``root_pitch + twist r / R`` from the zero-lift line, linear in
        the radius. The twist is the linear fit over 0.5-1 R of a constant-pitch propeller
        (``atan(p / (2 pi r))``, 4.5-inch pitch); the root pitch makes the hover thrust that of ``k_thrust``
        (:meth:`blade_element_hover`: 1.5702e-5 N s^2 against 1.57e-5; the pitch at 0.75 R, 0.30 rad,
        includes the zero-lift angle of the cambered section).
    profile_drag : float
        0.046: section profile drag coefficient C_d0 (low-Reynolds-number propeller sections, Re ~ 5e4), chosen
        so that the hover torque is that of ``k_torque`` (:meth:`blade_element_hover`: 2.4988e-7 N m s^2
        against 2.5e-7; figure of merit 0.71).
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
    k_inflow: float = 0.0
    k_rotor_drag: float = 1.2e-4
    k_flapping: float = 0.0
    drag_area: float = 0.04
    air_density: float = 1.225
    k_weathervane: float = 8e-4
    omega_min: float = 60.0
    omega_max: float = 1100.0
    reversible_rotors: bool = False
    # appended after reversible_rotors: the kernels read the vector of to_array() by position
    cg_x: float = 0.0
    cg_y: float = 0.0
    blade_element: bool = True
    blades: float = 2.0
    rotor_radius: float = 0.127
    chord: float = 0.02
    lift_slope: float = 5.7
    root_pitch: float = 0.50
    twist: float = -0.27
    profile_drag: float = 0.046

    def __post_init__(self) -> None:
        for name in ("reversible_rotors", "blade_element"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise TypeError(f"{name} must be a bool, got {getattr(self, name)!r}")
        for name in ("cg_x", "cg_y", "twist"):
            v = getattr(self, name)
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real) or not np.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
        for f in fields(self):
            if f.name in ("reversible_rotors", "blade_element", "cg_x", "cg_y", "twist"):
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
        if self.blade_element and self.blade_element_hover()[0] <= 0.0:
            raise ValueError("root_pitch, twist: the blade-element rotor makes no thrust in hover with this geometry "
                             f"(root_pitch={self.root_pitch!r}, twist={self.twist!r})")

    def blade_element_hover(self) -> tuple[float, float]:
        """Static thrust and torque coefficients ``(T / Omega^2, Q / Omega^2)`` (N s^2, N m s^2) of one
        blade-element rotor in hover (uniform momentum inflow ``v_i = sqrt(T / (2 rho pi R^2))``, solved in
        closed form): what ``k_thrust`` and ``k_torque`` are for the lumped rotor."""
        rho, R, a = self.air_density, self.rotor_radius, self.lift_slope
        k = rho * self.blades * self.chord * R
        # per unit tip speed^2: T = k a / 2 (th / 3 - l / 2), l = v_i / V_t, and T = 2 rho pi R^2 l^2 V_t^2
        th = self.root_pitch / 3.0 + self.twist / 4.0
        # 2 rho pi R^2 l^2 + k a l / 4 - k a th / 2 = 0
        qa, qb, qc = 2.0 * rho * np.pi * R * R, k * a / 4.0, -k * a * th / 2.0
        lam = (-qb + np.sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa) if qc < 0 else 0.0
        ct = 2.0 * rho * np.pi * R * R * lam * lam
        cq = k * R * (0.5 * a * lam * (th - lam / 2.0) + self.profile_drag / 8.0)
        return float(ct * R * R), float(cq * R * R)

    def to_array(self) -> np.ndarray:
        return np.array([getattr(self, f.name) for f in fields(self)], dtype=float)

    def to_dict(self) -> dict:
        return asdict(self)


#: Bidirectional rotors, lumped rotor coefficients, no rotor drag or weathervane: tsfdi's shipped aircraft
#: until the blade-element aircraft became the default (issue 30), kept for comparison only. With it the
#: controller flies its single hover design (no gain schedule: the schedule is computed for blade-element
#: aircraft), and ``simulate_hexacopter(params=BIDIRECTIONAL_HEXACOPTER)`` reproduces that simulator's records
#: bit for bit (``tests/datasets/test_hexacopter.py::test_bidirectional_preset_reproduces_the_old_records``).
BIDIRECTIONAL_HEXACOPTER = HexacopterParameters(k_inflow=7.2e-4, k_rotor_drag=0.0, k_flapping=4e-6,
                                                k_weathervane=0.0, reversible_rotors=True, blade_element=False)


@dataclass(frozen=True)
class ControllerGains:
    """Gains of the cascade controller (paper's Fig. 2), designed at hover by pole placement.

    The blade-element aircraft schedules the altitude, attitude and yaw-rate gains over the forward speed from this
    hover design (:func:`tsfdi.datasets.hexacopter.gain_schedule`); the numbers below are the hover design,
    computed on the lumped-rotor aircraft whose hover thrust and torque the blade-element rotor matches.

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
    values and the thrust-linear mixer (see :mod:`tsfdi.datasets.hexacopter`) no record of the bidirectional
    preset's design (240 x 60 s, severe turbulence included) is lost, and the heading is held after the failure
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
_FLEET_MAX = {"mass": 0.5, "cg_offset": 0.1, "motor_constant": 0.5, "inertia": 0.5, "payload": 0.5}


@dataclass(frozen=True)
class FleetSpread:
    """Spreads of a fleet of aircraft of one type that differ slightly in weight and handling (payloads).

    Hansen et al. (tsfdi's paper 002) analyse aircraft "of the same type but with small differences in weight and
    handling due to payloads"; with ``fleet=FleetSpread()`` each record of :func:`~tsfdi.datasets.simulate_hexacopter`
    / :func:`~tsfdi.datasets.make_hexacopter_dataset` flies its own aircraft drawn around the nominal
    :class:`HexacopterParameters`. Every quantity is drawn **uniformly and independently** in the interval given
    below (so a drawn value never leaves it), with one call ``rng.uniform(-1, 1, 6)`` of
    ``rng = numpy.random.default_rng([seed, FLEET_SEED_KEY])`` (``seed``: the record's seed), in the order mass,
    cg_x, cg_y, motor_constant, inertia, payload (the first five are the draws of the five-spread fleet before
    ``payload`` was added): a record's aircraft depends only on its seed, and a spread set to 0 leaves that
    quantity nominal without changing the others.

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
        lumped rotors and the ``chord`` of the blade-element rotors (another propeller batch: thrust and torque
        scale with the solidity at a given inflow).
    inertia : float
        0.05, relative: one factor ``1 + inertia * U`` multiplies ``ixx``, ``iyy`` and ``izz`` (payload and
        battery placement).
    payload : float
        0 (no payload), fraction of the gross weight: a payload fraction ``p`` is drawn uniformly in
        ``[0, payload]`` (``p = payload * (U + 1) / 2``) and the record's mass is its airframe mass (nominal times
        the ``mass`` factor) divided by ``1 - p``; issue 30 asks for 0-30 % (``payload=0.3``). The payload sits at
        the centre of gravity (inertia: the ``inertia`` factor only).

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
    payload: float = 0.0

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

        ``values`` holds ``mass`` (kg, payload included), ``cg_x`` and ``cg_y`` (m), the factors
        ``motor_constant`` and ``inertia`` (1: nominal) and ``payload`` (fraction of the gross weight), the record
        coordinates of the simulated dataset.
        """
        u = np.random.default_rng([int(seed), FLEET_SEED_KEY]).uniform(-1.0, 1.0, 6)
        kmot = 1.0 + self.motor_constant * u[3]
        kin = 1.0 + self.inertia * u[4]
        pay = self.payload * (u[5] + 1.0) / 2.0
        mass = params.mass * (1.0 + self.mass * u[0])
        values = {"mass": mass / (1.0 - pay) if pay else mass,
                  "cg_x": params.cg_x + self.cg_offset * u[1], "cg_y": params.cg_y + self.cg_offset * u[2],
                  "motor_constant": kmot, "inertia": kin, "payload": pay}
        drawn = replace(params, mass=values["mass"], cg_x=values["cg_x"], cg_y=values["cg_y"],
                        k_thrust=params.k_thrust * kmot, k_torque=params.k_torque * kmot,
                        chord=params.chord * kmot if params.blade_element else params.chord,
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
