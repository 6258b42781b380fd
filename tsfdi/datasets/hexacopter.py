"""Nonlinear 6-DOF hexacopter with Dryden turbulence, a cascade controller and abrupt rotor failures.

This is tsfdi's own generator of the data the study of Dutta et al. ("Statistical Time Series Methods for
Multicopter Fault Detection and Identification", sections "Hexacopter model and data generation" and
"Data Generation", Table 1) is built on: a hexacopter flying at 5 m/s through Dryden turbulence,
healthy or with rotor 1, 2 or 6 failed at 10 s, 60 s records at 1 kHz decimated to 100 Hz.

Notes
-----
**Rigid body** (paper's eq. 1): states :math:`x = (X, Y, Z, \\phi, \\theta, \\psi, u, v, w, p, q, r)` in a
north-east-down frame and body axes (x forward, y right, z down), Z-Y-X Euler angles,

.. math::

    m(\\dot{\\mathbf v} + \\boldsymbol\\omega \\times \\mathbf v) = \\mathbf F, \\qquad
    I \\dot{\\boldsymbol\\omega} + \\boldsymbol\\omega \\times I \\boldsymbol\\omega = \\mathbf M, \\qquad
    \\dot{\\mathbf X} = R(\\phi, \\theta, \\psi) \\mathbf v,

plus the six rotor speeds with a first-order lag :math:`\\dot\\Omega_i = (\\Omega_{c,i} - \\Omega_i)/\\tau_m`.

**Rotors.** Rotor ``i`` (1..6) sits at azimuth :math:`(i-1) 60^\\circ` from the nose, clockwise seen from
above: rotor 1 front, rotor 2 front-right, rotor 6 front-left. Rotor 1 spins clockwise seen from above and
the directions alternate (1, 3, 5 clockwise, :math:`s_i = +1`; 2, 4, 6 counter-clockwise, :math:`s_i = -1`).
The hub velocity relative to the air is :math:`\\mathbf v_h = (\\mathbf v - \\mathbf v_g) +
(\\boldsymbol\\omega - \\boldsymbol\\omega_g) \\times \\mathbf r_i` (gusts :math:`\\mathbf v_g = (u_g, v_g,
w_g)`, :math:`\\boldsymbol\\omega_g = (p_g, q_g, r_g)` from :mod:`tsfdi.datasets.dryden`, applied in body axes
as in MIL-F-8785C) and the rotor speed relative to the air :math:`\\bar\\Omega_i = \\Omega_i + s_i (r - r_g)`
(the motor holds :math:`\\Omega_i` relative to the turning airframe).

*Blade-element rotor* (the default, ``blade_element=True``). A fixed-pitch rotor of ``blades`` blades of
radius :math:`R`, chord :math:`c`, lift slope :math:`a`, pitch :math:`\\theta_0 + \\theta_{tw} r/R` and profile
drag :math:`C_{d0}`, rigid blades, quasi-steady strip theory integrated in closed form over the radius and the
azimuth (Leishman, *Principles of Helicopter Aerodynamics*, ch. 3; Johnson, *Helicopter Theory*, ch. 5;
Bangura & Mahony 2012 for small propellers). With :math:`k = \\rho N c R` (:math:`= \\rho A \\sigma`), tip speed
:math:`V_t = \\bar\\Omega R`, in-plane speed :math:`V_h = |(v_{h,x}, v_{h,y})|` and the flow down through the
disc :math:`V_n = v_i - v_{h,z}` (:math:`v_i` the induced velocity):

.. math::

    T &= k \\tfrac a2 \\left[\\theta_0 (\\tfrac{V_t^2}{3} + \\tfrac{V_h^2}{2}) + \\theta_{tw} \\tfrac{V_t^2 + V_h^2}{4}
          - \\tfrac{V_n V_t}{2}\\right], \\qquad
    Q = k R \\left[\\tfrac a2 V_n (\\tfrac{\\theta_0 V_t}{3} + \\tfrac{\\theta_{tw} V_t}{4} - \\tfrac{V_n}{2})
          + C_{d0} \\tfrac{V_t^2 + V_h^2}{8}\\right], \\\\
    \\mathbf H &= -k \\left[\\tfrac a4 V_n (\\tfrac{\\theta_0}{2} + \\tfrac{\\theta_{tw}}{3})
          + \\tfrac{C_{d0} V_t}{4}\\right] (v_{h,x}, v_{h,y}), \\qquad
    \\mathbf M_R = s_i\\, k R \\tfrac a2 (\\tfrac{\\theta_0 V_t}{3} + \\tfrac{\\theta_{tw} V_t}{4} - \\tfrac{V_n}{4})
          (v_{h,x}, v_{h,y}),

(in coefficient form :math:`C_T = \\tfrac{\\sigma a}{2}[\\theta_0(\\tfrac13 + \\tfrac{\\mu^2}{2}) +
\\tfrac{\\theta_{tw}}{4}(1 + \\mu^2) - \\tfrac\\lambda2]`, :math:`C_H = \\tfrac{\\sigma C_{d0}\\mu}{4} +
\\tfrac{\\sigma a}{4}\\lambda\\mu(\\tfrac{\\theta_0}{2} + \\tfrac{\\theta_{tw}}{3})`): thrust :math:`T` along
:math:`-z`, torque :math:`Q` (reaction :math:`-s_i Q` on the body about :math:`z`), the H-force (rotor drag) against
the in-plane hub velocity, and the rolling hub moment :math:`\\mathbf M_R` of the advancing blade (towards the
retreating side, so its sign follows the spin). With a longitudinal inflow gradient
:math:`v_i (1 + k_x \\tfrac rR \\cos\\psi)`, :math:`k_x = \\tfrac{15\\pi}{32}\\tan\\tfrac\\chi2` (Pitt & Peters
1981; :math:`\\tan\\tfrac\\chi2 = V_h / (\\sqrt{V_h^2 + V_n^2} + \\max(V_n, 0))`), the disc's front lifts more:
pitching hub moment :math:`k R a v_i V_t k_x / 16` towards the relative wind (nose up in forward flight). The
gradient changes neither :math:`T` nor :math:`\\mathbf H` (it averages out over the azimuth). The induced
velocity is a state per rotor, the zeroth (uniform) mode of the Pitt-Peters / Peters-He finite-state wake (the
paper uses 3 x 4 Peters-He states; this is its lowest mode):

.. math::

    \\tfrac83 \\rho R^3 \\dot v_i = T - 2 \\rho \\pi R^2 \\sqrt{V_h^2 + V_n^2}\\, v_i,

whose equilibrium is Glauert's momentum inflow in forward flight; its time constant is about 10 ms at hover
(apparent mass :math:`\\tfrac83\\rho R^3`), so RK4 at 1 kHz integrates it accurately, it never divides by zero
and needs no iteration. The geometry is a two-blade 10-inch propeller whose hover thrust and torque equal the
lumped coefficients within 0.1 % (:meth:`HexacopterParameters.blade_element_hover`, tested in
``test_blade_element_hover_matches_the_lumped_coefficients``). The blade elements may give a slightly negative
thrust at idle when the air comes down through the disc fast (windmill-brake state): that is kept, it is the
physics of a fixed-pitch propeller; the rotor speed itself never reverses. ``k_rotor_drag`` and ``k_flapping``
add lumped H-force and flapping moment for flexible blades (0 by default).

*Lumped rotor* (``blade_element=False``, :data:`BIDIRECTIONAL_HEXACOPTER`): thrust :math:`T_i = k_T \\bar\\Omega_i
|\\bar\\Omega_i| + k_w |\\bar\\Omega_i| v_{h,z}`, torque :math:`Q_i = k_Q \\bar\\Omega_i |\\bar\\Omega_i|`, rotor drag
:math:`-k_h |\\bar\\Omega_i| (v_{h,x}, v_{h,y})`, blade-flapping moment :math:`k_f |\\bar\\Omega_i| (-v_{h,y},
v_{h,x}, 0)`; with ``reversible_rotors`` the speeds range over :math:`[-\\Omega_{max}, \\Omega_{max}]`.

*One-way rotors* (default): the mixer clips every command to ``[omega_min, omega_max]`` and the first-order
motor then stays in that range (tested at 1 kHz in
``test_one_way_rotors_never_reverse_and_commands_saturate``). The body adds drag :math:`-\\rho C_D A |\\mathbf
v_r| \\mathbf v_r/2` and a weathervane yaw moment :math:`k_n |v_{r,h}| v_{r,y}`. A failed rotor's thrust, torque,
H-force and hub moments are zero from the failure time on (its wake decays; the motor keeps following its
command, as after the loss of a propeller); ``test_failed_rotor_makes_no_load``. A partial loss of effectiveness
(``failure_level`` < 1) multiplies them by ``1 - failure_level`` instead (``test_partial_loss_scales_the_loads``).

**Controller** (spirit of the paper's Fig. 2, no adaptation after a failure): a PI velocity loop in the
north-east frame (integrators in world axes, the tilt command limited in magnitude and rotated into the
heading frame every step, so it stays right while the aircraft turns) sets the pitch and roll commands;
PID loops on altitude, roll and pitch and a heading loop (P on the heading error wrapped to
:math:`(-\\pi, \\pi]`, giving a limited yaw-rate command, then a PI yaw-rate loop) produce the four
controls of eq. 2 (:math:`\\Omega_0, \\Omega_R, \\Omega_P, \\Omega_Y`, rad/s) which a fixed mixer turns
into rotor speed commands. The mixer is thrust-linear, as in flight-control firmware (thrust linearisation
of ArduPilot's ``MOT_THST_EXPO``, PX4's ``THR_MDL_FAC``): the controls are rotor-speed deviations about
the collective speed, mixed in thrust,

.. math::

    \\Omega_{c,i}^2 = \\Omega_0^2 + 2 \\Omega_0 (-\\sin\\psi_i \\Omega_R + \\cos\\psi_i \\Omega_P
    \\mp \\Omega_Y),

which is eq. 2 (:math:`\\Omega_{c,i} = \\Omega_0 - \\sin\\psi_i \\Omega_R + \\cos\\psi_i \\Omega_P
\\mp \\Omega_Y`) to first order, but makes a control change the thrust and torque of every rotor by the
same amount whatever its speed. With a speed-linear mixer a rotor running slow -- the one opposite a
failed rotor -- makes only a fraction of its share of the roll, pitch and yaw moments
(:math:`\\partial T/\\partial\\Omega = 2 k_T \\Omega`), so in gusts the loops work much harder and the yaw
authority is lost more often; the squared deviations also add thrust that then vanishes in saturation.
Priorities: thrust, roll and pitch first -- :math:`|\\Omega_Y|` is limited to ``max_yaw_control`` times
:math:`1 - (|e_\\phi| + |e_\\theta|)/` ``yaw_priority_error`` (no yaw authority while the attitude
error is large), collective/roll/pitch are clipped to the speed limits before the yaw term is added, and
each rotor takes the yaw term only as far as its own limits allow (a dead rotor whose command the pitch
loop drives up does not take the yaw authority of the five others). The yaw-rate integrator only unwinds
while :math:`\\Omega_Y` is limited or less than 75 % of the yaw term reaches the rotors (anti-windup). One
gain set (:class:`ControllerGains`) serves every record and turbulence level.

*Gain schedule* (the paper: "designed at multiple trim points, with gain scheduling between these points"). The
gains of :class:`ControllerGains` are a hover design. :func:`gain_schedule` trims the aircraft at
:data:`SCHEDULE_SPEEDS` (0-14 m/s every 2 m/s), computes the effectiveness of the four controls there
numerically (central differences through the mixer and the derivative), and scales each loop's gains by
:math:`E(0)/E(v)` so that gain times effectiveness -- the closed-loop poles of the hover design -- holds at each
trim point; the controller interpolates the factors linearly on its ground speed. The lumped-rotor preset flies
the fixed hover design (factors 1), which keeps its records bit for bit.

**Turbulence.** Dryden gusts (:mod:`tsfdi.datasets.dryden`) at the record's airspeed, with paper 003's "length
scale" 0.6096 m as the scale length of the three linear gusts (:data:`PAPER_SCALE_LENGTH`) and the MIL-F-8785C
low-altitude intensities of the light / moderate / severe levels times :data:`PAPER_INTENSITY_SCALE` (0.16), the
one factor chosen on the paper's published physical quantities (``docs/guide/hexacopter.md``); ``scale_length=
None, intensity_scale=1`` gives the standard's lengths and intensities.

*What a failure does here.* A planar PNPNPN hexacopter with one rotor failed can hold all four axes only
with the opposite rotor at (about) zero thrust (Du et al. 2015; Michieletto et al. 2018). One-way rotors cannot go
below their idle speed, so after a failure the default aircraft holds roll, pitch, altitude and speed but not
always its heading: the heading turns nose right after the loss of a clockwise rotor (1, 3, 5: its reaction
torque is lost) and nose left after a counter-clockwise one (2, 4, 6; ``test_spin_direction_sets_the_sign_of_the
_yaw_transient``), and in turbulence the opposite rotor switches on and off its idle floor and the heading may
keep slipping. How far depends on the turbulence. In the shipped design (paper's turbulence settings,
:data:`PAPER_SCALE_LENGTH` and :data:`PAPER_INTENSITY_SCALE`; ``data/README.md``) no record is lost and the heading
is held: over 30-60 s its range has a median of 0.04-0.05 rad after a failure in light, 0.07-0.09 rad in moderate
and 0.10-0.17 rad in severe turbulence (healthy 0.02, 0.05, 0.07 rad). With the standard's intensities
(``intensity_scale=1``, ``scale_length=None``) it slips by turns in severe turbulence (the MIL-F-8785C column
of ``docs/figures/hexacopter_quantities.md``, where the heading ranges above are computed too). At hover the
aircraft with a failed rotor keeps turning slowly without any turbulence (``test_hover_heading_after_failure_needs_the_opposite_rotor_to_stop``). The bidirectional preset
(:data:`BIDIRECTIONAL_HEXACOPTER`) can reverse the opposite rotor and holds its heading after the failure at
every turbulence level (its tests in ``tests/datasets/test_hexacopter.py``). ``yaw`` is the unwrapped heading;
a record that loses the aircraft is flagged in ``lost_control``.

**Fleet and operating points.** By default every record flies the same aircraft at the same speed. With
``fleet=FleetSpread(...)`` (Hansen et al.: aircraft "of the same type but with small differences in weight and
handling due to payloads") each record flies its own: airframe mass, payload (fraction of the gross weight),
centre-of-gravity offset (``cg_x``, ``cg_y``: the rotor arms are then measured from the offset centre of
gravity), rotor constants (chord of the blade-element rotor, ``k_thrust``/``k_torque`` of the lumped one) and
inertia are drawn uniformly around the nominal parameters from the record's seed (:class:`FleetSpread`),
independently of its gusts, and stored as record coordinates. With ``speed=(low, high)`` each record's speed
is drawn from its seed too (coordinate ``speed``). Each record starts at its own trim, at its own speed, with the
controller's integrators holding it; the mixer and the gain schedule are those of the nominal aircraft.

**Integration.** Fixed-step classical Runge-Kutta (RK4) at 1 kHz (24 states: rigid body, six rotor speeds, six
induced velocities); the controller and the gusts are held constant over a step (sampled-data controller at
1 kHz). The specific force ``ax, ay, az`` (rotor and aerodynamic forces over the mass, body axes: what an
accelerometer at the centre of gravity measures) comes from the first RK4 stage of each step, ``rotor_speed<i>``
is the motor state and ``motor_command<i>`` the mixer output at that step. Each record is integrated on its own
(numba-compiled, records in parallel), so a record depends only on its own seed and configuration.

**Decimation.** From 1000 Hz to 100 Hz with :func:`scipy.signal.resample_poly` (polyphase zero-phase FIR,
Kaiser window beta 5, 201 taps, cut-off at the new Nyquist frequency 50 Hz, edges padded by linear
extrapolation): zero phase keeps the attitude aligned with the failure time. A low-pass filter rings at the corners
of clipped signals: decimated motor commands and rotor speeds can leave ``[omega_min, omega_max]`` by a few
rad/s; ``fs=1000`` (no decimation) gives the integration samples themselves.

References
----------
.. [1] A. Dutta, M. McKay, F. Kopsaftopoulos, F. Gandhi, "Statistical Time Series Methods for Multicopter
       Fault Detection and Identification", VFS Forum (paper 003 in tsfdi's papers).
.. [2] G.-X. Du, Q. Quan, K.-Y. Cai, "Controllability analysis and degraded control for a class of
       hexacopters subject to rotor failures", J. Intell. Robot. Syst. 78, 2015 (a PNPNPN hexacopter with
       one rotor failed cannot hold all four axes).
.. [3] G. Michieletto, M. Ryll, A. Franchi, "Fundamental actuation properties of multirotors:
       force-moment decoupling and fail-safe robustness", IEEE Trans. Robotics 34(3), 2018 (a planar
       hexarotor is not fail-safe for one rotor loss; a tilted one is).
.. [4] R. Mahony, V. Kumar, P. Corke, "Multirotor Aerial Vehicles: Modeling, Estimation, and Control of
       Quadrotor", IEEE Robotics & Automation Magazine 19(3), 2012.
.. [5] J. G. Leishman, "Principles of Helicopter Aerodynamics", 2nd ed., Cambridge University Press, 2006
       (blade element and momentum theory, ch. 2-3; dynamic inflow, ch. 10).
.. [6] W. Johnson, "Helicopter Theory", Princeton University Press, 1980 (rotor forces in forward flight).
.. [7] D. M. Pitt, D. A. Peters, "Theoretical prediction of dynamic-inflow derivatives", Vertica 5, 1981.
.. [8] M. Bangura, R. Mahony, "Nonlinear dynamic modeling for high performance control of a quadrotor",
       ACRA 2012.
"""

from __future__ import annotations

import functools
import inspect
import os
from typing import Any

import numpy as np
from scipy import optimize, signal

from tsfdi._validation import MAX_VALUES, boolean, check_rng, float_like, int_like, option
from tsfdi.datasets import _hexacopter_core as _core
from tsfdi.datasets._hexacopter_params import (
    BIDIRECTIONAL_HEXACOPTER,
    FLEET_SEED_KEY,
    ControllerGains,
    FleetSpread,
    HexacopterParameters,
)
from tsfdi.datasets.dryden import INTENSITIES, DrydenTurbulence, draw_gusts

__all__ = ["HexacopterParameters", "BIDIRECTIONAL_HEXACOPTER", "ControllerGains", "FleetSpread", "FLEET_SEED_KEY",
           "trim", "gain_schedule", "SCHEDULE_SPEEDS", "SPEED_SEED_KEY", "simulate_hexacopter", "make_hexacopter_dataset",
           "write_hexacopter_dataset", "FLEET_COORDS", "PAPER_SCALE_LENGTH", "PAPER_INTENSITY_SCALE",
           "CHANNELS", "STATES", "TURBULENCE_LEVELS", "encode_for_file", "hexacopter_signals", "SIGNAL_CHANNELS"]

#: Output channels and their units.
CHANNELS = {
    "x": "m", "y": "m", "z": "m",
    "roll": "rad", "pitch": "rad", "yaw": "rad",
    "u": "m/s", "v": "m/s", "w": "m/s",
    "p": "rad/s", "q": "rad/s", "r": "rad/s",
    "collective": "rad/s", "roll_control": "rad/s", "pitch_control": "rad/s", "yaw_control": "rad/s",
    "roll_command": "rad", "pitch_command": "rad", "yaw_command": "rad",
    "ax": "m/s^2", "ay": "m/s^2", "az": "m/s^2",
    **{f"rotor_speed{i}": "rad/s" for i in range(1, 7)},
    **{f"motor_command{i}": "rad/s" for i in range(1, 7)},
}
_DESCRIPTIONS = {
    "x": "north position", "y": "east position", "z": "down position (NED)",
    "roll": "roll angle phi", "pitch": "pitch angle theta", "yaw": "heading psi (unwrapped)",
    "u": "body x velocity", "v": "body y velocity", "w": "body z velocity",
    "p": "roll rate", "q": "pitch rate", "r": "yaw rate",
    "collective": "collective control Omega_0 (eq. 2)", "roll_control": "roll control Omega_R (eq. 2)",
    "pitch_control": "pitch control Omega_P (eq. 2)", "yaw_control": "yaw control Omega_Y (eq. 2)",
    "roll_command": "commanded roll", "pitch_command": "commanded pitch", "yaw_command": "commanded heading",
    "ax": "specific force, body x (accelerometer at the centre of gravity: rotor and aerodynamic forces / mass)",
    "ay": "specific force, body y (accelerometer at the centre of gravity)",
    "az": "specific force, body z (down; about -g in hover)",
    **{f"rotor_speed{i}": f"speed of rotor {i} relative to the airframe (motor state)" for i in range(1, 7)},
    **{f"motor_command{i}": f"speed command of rotor {i} (mixer output, within [omega_min, omega_max])"
       for i in range(1, 7)},
}
STATES = ("healthy", "rotor1", "rotor2", "rotor6")
TURBULENCE_LEVELS = ("none",) + tuple(INTENSITIES)

#: Record coordinates of a fleet (``fleet=FleetSpread(...)``): name -> (units, description).
FLEET_COORDS = {
    "mass": ("kg", "mass of the record's aircraft"),
    "cg_x": ("m", "centre-of-gravity offset forward of the hub centre"),
    "cg_y": ("m", "centre-of-gravity offset right of the hub centre"),
    "motor_constant": ("1", "factor on k_thrust and k_torque (1: nominal)"),
    "inertia": ("1", "factor on ixx, iyy, izz (1: nominal)"),
    "payload": ("1", "payload as a fraction of the gross weight (0: none)"),
}

#: Forward speeds (m/s) of the trim points of the gain schedule (:func:`gain_schedule`).
SCHEDULE_SPEEDS = (0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0)
#: Second entropy word of the generator of a record's forward speed when ``speed`` is a range: ``uniform(low,
#: high)`` of ``numpy.random.default_rng([seed, SPEED_SEED_KEY])`` (independent of the gusts and the fleet draw).
SPEED_SEED_KEY = 0x5BEED

#: Bounds beyond which a record is flagged ``lost_control`` (roll, pitch in rad; altitude error in m); a
#: record is also lost when the aircraft reaches the ground (altitude below 0).
LOSS_LIMITS = (1.2, 1.2, 20.0)


def trim(speed: float = 5.0, *, params: HexacopterParameters | None = None,
         altitude: float = 5.0) -> dict:
    """Steady level flight north at ``speed`` (m/s) without turbulence.

    Solves the longitudinal force and pitching-moment balance for pitch angle, collective and pitch
    control (roll and yaw controls are zero by symmetry of the alternating rotor directions) of the lumped-rotor
    aircraft. The blade-element rotors' rolling hub moments and the yaw torques of rotors at different speeds
    break that symmetry, as does a lateral centre-of-gravity offset (``params.cg_y != 0``): the six force and
    moment balances are then solved for roll, pitch and the four controls.

    Returns
    -------
    dict
        ``state`` (24: rigid body, rotor speeds, induced velocities of the blade-element rotors at their
        equilibrium; 0 for the lumped rotor), ``integrators`` (6), ``controls``
        (Omega_0, Omega_R, Omega_P, Omega_Y), ``residual`` (max abs derivative at the trim).
    """
    speed = float_like(speed, "speed", minimum=0.0)
    altitude = float_like(altitude, "altitude", minimum=0.0, strict_min=True)
    params = HexacopterParameters() if params is None else params
    if not isinstance(params, HexacopterParameters):
        raise TypeError("params must be a HexacopterParameters")
    P = params.to_array()
    alive = np.ones(6)
    g0 = np.zeros(6)
    az = np.arange(6) * np.pi / 3

    def build(z):
        th, om0, omp = z
        x = np.zeros(_core.N_X)
        x[2] = -altitude
        x[4] = th
        x[6] = speed * np.cos(th)
        x[8] = speed * np.sin(th)
        # rotor speeds of the thrust-linear mixer (collective and pitch control only)
        x[12:18] = np.sqrt(om0 * om0 + 2.0 * om0 * np.cos(az) * omp)
        return _steady_inflow(x, P)

    def resid(z):
        x = build(z)
        d = _core.derivative(x, x[12:18], g0, P, alive)
        return [d[6], d[8], d[10] * params.iyy]

    kt = params.blade_element_hover()[0] if params.blade_element else params.k_thrust
    om_h = np.sqrt(params.mass * params.gravity / (6 * kt))
    if params.cg_y != 0.0 or params.blade_element:
        return _trim_asymmetric(speed, altitude, params, om_h)
    sol, info, ier, msg = optimize.fsolve(resid, [0.0, om_h, 0.0], full_output=True, xtol=1e-14)
    # (fsolve may stop at machine precision with ier != 1; the balance residual decides)
    if ier != 1 and np.max(np.abs(resid(sol))) > 1e-10:
        raise ValueError(f"speed={speed} m/s: the aircraft has no trim (steady level flight) at this speed "
                         f"({msg.strip()})")
    x = build(sol)
    d = _core.derivative(x, x[12:18], g0, P, alive)
    integ = np.array([sol[0], 0.0, sol[1], 0.0, sol[2], 0.0])
    return {"state": x, "integrators": integ, "controls": np.array([sol[1], 0.0, sol[2], 0.0]),
            "residual": float(np.max(np.abs(d[3:12])))}


def _trim_asymmetric(speed: float, altitude: float, params: HexacopterParameters, om_h: float) -> dict:
    """:func:`trim` of an aircraft without lateral symmetry: roll, pitch and the four controls of the mixer."""
    P = params.to_array()
    alive = np.ones(6)
    g0 = np.zeros(6)
    az = np.arange(6) * np.pi / 3
    yaw_sign = np.array([-1.0, 1.0, -1.0, 1.0, -1.0, 1.0])  # the controller's mixer (rotor 1 clockwise)
    inertia = np.array([params.ixx, params.iyy, params.izz])

    def build(z):
        ph, th, om0, omr, omp, omy = z
        x = np.zeros(_core.N_X)
        x[2] = -altitude
        x[3] = ph
        x[4] = th
        # body velocity of level flight north at ``speed`` (heading 0)
        x[6:9] = speed * np.array([np.cos(th), np.sin(ph) * np.sin(th), np.cos(ph) * np.sin(th)])
        c2 = om0 * om0 + 2.0 * om0 * (-np.sin(az) * omr + np.cos(az) * omp + yaw_sign * omy)
        x[12:18] = np.sign(c2) * np.sqrt(np.abs(c2))
        return _steady_inflow(x, P)

    def resid(z):
        x = build(z)
        d = _core.derivative(x, x[12:18], g0, P, alive)
        return np.concatenate([d[6:9], d[9:12] * inertia])

    sol, info, ier, msg = optimize.fsolve(resid, [0.0, 0.0, om_h, 0.0, 0.0, 0.0], full_output=True, xtol=1e-14)
    if ier != 1 and np.max(np.abs(resid(sol))) > 1e-10:
        raise ValueError(f"speed={speed} m/s: the aircraft has no trim (steady level flight) at this speed "
                         f"({msg.strip()})")
    x = build(sol)
    d = _core.derivative(x, x[12:18], g0, P, alive)
    ph, th, om0, omr, omp, omy = sol
    # integrators [I_theta, I_phi, I_collective, I_roll, I_pitch, I_yaw] that reproduce the trim (heading 0)
    integ = np.array([th, ph, om0, omr, omp, omy])
    return {"state": x, "integrators": integ, "controls": np.array([om0, omr, omp, omy]),
            "residual": float(np.max(np.abs(d[3:12])))}


def _steady_inflow(x: np.ndarray, P: np.ndarray) -> np.ndarray:
    """``x`` with the induced velocities ``x[18:24]`` of the blade-element rotors at their equilibrium (the
    momentum balance of each rotor, Glauert's formula), by Newton's method (the six are independent); a lumped
    rotor keeps 0."""
    if P[21] <= 0.0:
        return x
    x = x.copy()
    alive = np.ones(6)
    g0 = np.zeros(6)
    x[18:24] = 5.0
    for _ in range(60):
        f = _core.derivative(x, x[12:18], g0, P, alive)[18:24]
        xe = x.copy()
        xe[18:24] += 1e-6
        slope = (_core.derivative(xe, x[12:18], g0, P, alive)[18:24] - f) / 1e-6
        step = f / slope
        x[18:24] -= step
        if np.max(np.abs(step)) < 1e-13:
            break
    return x


@functools.lru_cache(maxsize=64)
def gain_schedule(params: HexacopterParameters | None = None) -> np.ndarray:
    """Gain factors of the controller over the forward speed: rows ``[speed, f_altitude, f_roll, f_pitch, f_yaw]``.

    The gains of :class:`ControllerGains` are the design at hover. At each speed of :data:`SCHEDULE_SPEEDS` the
    aircraft is trimmed (:func:`trim`) and the control effectiveness of the four controls of eq. 2 is computed
    numerically (central differences of +-1 rad/s through the mixer, rotor speeds and inflow at their new
    equilibrium -- the inflow settles in about 10 ms, far faster than the loops): ``dw/dt`` per rad/s of
    collective, ``dp/dt``, ``dq/dt`` and ``dr/dt`` per rad/s of roll, pitch and yaw control. Design rule: each
    loop's gains (altitude: ``k_altitude, kd_altitude, ki_altitude``; roll and pitch: ``k_attitude, k_rate,
    ki_attitude``; yaw rate: ``k_yaw_rate, ki_yaw_rate``) are multiplied by ``E(0) / E(v)``, so that gain times
    effectiveness -- the closed-loop poles of the hover design, aerodynamic damping aside -- is the same at
    every trim point. The controller interpolates the factors linearly on its ground speed
    (``sqrt(v_n^2 + v_e^2)``) and holds the end values beyond 14 m/s. The velocity and heading loops are not
    scheduled (tilt acts on the acceleration through gravity, the same at every speed).

    A lumped-rotor aircraft (``blade_element=False``, :data:`BIDIRECTIONAL_HEXACOPTER`) flies the fixed hover
    design: one row ``[0, 1, 1, 1, 1]``.

    Parameters
    ----------
    params : HexacopterParameters, optional
        The aircraft (default ``HexacopterParameters()``); a fleet flies the schedule of its nominal aircraft.

    Returns
    -------
    numpy.ndarray
        Shape ``(len(SCHEDULE_SPEEDS), 5)`` (read-only).
    """
    params = HexacopterParameters() if params is None else params
    if not isinstance(params, HexacopterParameters):
        raise TypeError("params must be a HexacopterParameters")
    if not params.blade_element:
        out = np.array([[0.0, 1.0, 1.0, 1.0, 1.0]])
        out.flags.writeable = False
        return out
    P = params.to_array()
    alive = np.ones(6)
    g0 = np.zeros(6)
    az = np.arange(6) * np.pi / 3
    yaw_sign = np.array([-1.0, 1.0, -1.0, 1.0, -1.0, 1.0])
    rows = []
    for v in SCHEDULE_SPEEDS:
        tr = trim(v, params=params)
        base = tr["state"]
        om0, omr, omp, omy = tr["controls"]
        eff = []
        for j, out_index in enumerate((8, 9, 10, 11)):
            d = []
            for delta in (1.0, -1.0):
                c = np.array([om0, omr, omp, omy])
                c[j] += delta
                x = base.copy()
                w2 = c[0] ** 2 + 2.0 * c[0] * (-np.sin(az) * c[1] + np.cos(az) * c[2] + yaw_sign * c[3])
                x[12:18] = np.sqrt(w2)
                x = _steady_inflow(x, P)
                d.append(_core.derivative(x, x[12:18], g0, P, alive)[out_index])
            eff.append(abs(d[0] - d[1]) / 2.0)
        rows.append([v] + eff)
    rows = np.array(rows)
    out = np.column_stack([rows[:, 0], rows[0, 1:] / rows[:, 1:]])
    out.flags.writeable = False
    return out


def _rotor_index(failed_rotor) -> int:
    if failed_rotor is None:
        return 0
    r = int_like(failed_rotor, "failed_rotor")
    if not 0 <= r <= 6:
        raise ValueError(f"failed_rotor must be 1..6 (0 or None: healthy), got {failed_rotor!r}")
    return r


#: largest commanded speed (m/s): the shipped aircraft has no trim much beyond 30 m/s
MAX_SPEED = 40.0


#: Dryden scale length (m) of the simulated data: paper 003 ("Data Generation") gives its Dryden model's "length
#: scale" as the hub-to-hub distance 0.6096 m; taken as the scale length of all three linear gusts.
PAPER_SCALE_LENGTH = 0.6096
#: Factor on the MIL-F-8785C low-altitude intensities (W20 15 / 30 / 45 kn for light / moderate / severe) of the
#: simulated data. Paper 003 does not publish its intensities; this one factor was chosen, with the scale length
#: above and nothing else, so that its published physical quantities come out within a factor of 3 on two
#: development seeds (the post-failure steady-state roll and pitch variances, the pitch AR order and RSS/SSS, the
#: VAR order; the heading's cannot with one-way rotors): ``docs/scripts/hexacopter_quantities.py``. With the
#: standard's intensities (1.0) and lengths the steady-state variances are tens to hundreds of times the
#: paper's (the MIL-F-8785C column of ``docs/figures/hexacopter_quantities.md``).
PAPER_INTENSITY_SCALE = 0.16


def simulate_hexacopter(records=None, *, duration: float = 60.0, speed=5.0,
                        turbulence="severe", failed_rotor=0, failure_time=10.0, failure_level=1.0, seed=0,
                        dt: float = 0.001, fs: float = 100.0, altitude: float = 5.0, span: float = 0.6096,
                        scale_length: float | None = PAPER_SCALE_LENGTH,
                        intensity_scale: float = PAPER_INTENSITY_SCALE,
                        params: HexacopterParameters | None = None, gains: ControllerGains | None = None,
                        fleet: FleetSpread | None = None, batch: int = 16):
    """Simulate hexacopter records at 1/dt Hz and return them decimated to ``fs`` as an xarray Dataset.

    Parameters
    ----------
    records : int, optional
        Number of records. ``turbulence``, ``failed_rotor``, ``failure_time`` and ``seed`` may be scalars
        (shared) or sequences of this length; when omitted it is their common length (or 1).
    duration : float
        Record length in seconds (> 0).
    speed : float or (float, float)
        Commanded ground speed north in m/s (0 to 40); also the Dryden airspeed (floored at 1 m/s). A pair
        ``(low, high)``: each record's speed is drawn uniformly in ``[low, high]`` from
        ``numpy.random.default_rng([seed, SPEED_SEED_KEY])`` with the record's seed (independent of its gusts and
        fleet draw); the record is trimmed at its speed, flown with the scheduled gains (:func:`gain_schedule`),
        its Dryden model uses its speed, and the ``speed`` coordinate holds it.
    turbulence : {"none", "light", "moderate", "severe"} or sequence
        Dryden intensity per record.
    failed_rotor : int or sequence
        1..6 for the rotor that fails abruptly at ``failure_time``, 0 (or None) for a healthy record.
    failure_time : float or sequence
        Failure instant in seconds (0 <= failure_time < duration); ignored for healthy records.
    failure_level : float or sequence
        Fraction (0 < level <= 1) of the failed rotor's effectiveness lost at ``failure_time``: from then on its
        thrust, torque, H-force and hub moments are ``1 - level`` times those of a healthy rotor at the same speed
        and inflow, and its wake is driven by the reduced thrust (a partial loss of rotor effectiveness, e.g. a
        damaged propeller). 1.0 (default): the abrupt loss of the whole rotor, bit for bit the records simulated
        before this option existed. Ignored for healthy records (coordinate NaN there).
    seed : int or sequence of int
        Per-record seed of the turbulence noise (``numpy.random.default_rng(seed)``); a record depends
        only on its own seed and configuration, so any subset can be regenerated alone, bit for bit.
    dt : float
        Integration step in seconds (> 0); ``1/dt`` must be an integer multiple of ``fs``.
    fs : float
        Output sampling frequency in Hz.
    altitude, span : float
        Flight altitude (m) and Dryden span (m).
    scale_length : float or None
        Dryden scale length (m) of all three linear gusts (:class:`~tsfdi.datasets.DrydenTurbulence`); default
        :data:`PAPER_SCALE_LENGTH` (paper 003's 0.6096 m); ``None``: the MIL-F-8785C low-altitude lengths of
        ``altitude``.
    intensity_scale : float
        Factor (> 0) on the MIL-F-8785C intensities of each turbulence level; default
        :data:`PAPER_INTENSITY_SCALE` (chosen on paper 003's published physical quantities); 1: the standard's.
    params, gains : optional
        :class:`HexacopterParameters` and :class:`ControllerGains`.
    fleet : FleetSpread, optional
        None (default): every record flies the aircraft ``params``. A :class:`FleetSpread`: each record flies
        its own aircraft drawn around ``params`` from its seed (:meth:`FleetSpread.draw`; the gusts are the
        same as without a fleet), trimmed for its own parameters; the drawn values are the record coordinates
        ``mass``, ``cg_x``, ``cg_y``, ``motor_constant`` and ``inertia`` (:data:`FLEET_COORDS`).
    batch : int
        Records integrated per chunk (memory: ``batch * duration / dt * 19 * 8`` bytes).

    Returns
    -------
    xarray.Dataset
        One variable per channel (see :data:`CHANNELS`: the states, the controls of eq. 2, the specific force
        ``ax, ay, az``, the rotor speeds and the motor commands), dims ``(record, time)``, units in ``attrs``;
        per-record coordinates ``state``, ``turbulence``, ``speed``, ``seed``, ``failure_time``,
        ``failure_level``, ``failed_rotor`` and the variable ``lost_control`` (True where roll or pitch exceeded 1.2 rad, the
        altitude error 20 m or the aircraft reached the ground; the record is NaN from then on); with a
        ``fleet`` also the coordinates of :data:`FLEET_COORDS` and the attribute ``fleet``.
    """
    plan = _plan(records, duration=duration, speed=speed, turbulence=turbulence, failed_rotor=failed_rotor,
                 failure_time=failure_time, failure_level=failure_level, seed=seed, dt=dt, fs=fs, altitude=altitude, span=span,
                 scale_length=scale_length, intensity_scale=intensity_scale, params=params, gains=gains, fleet=fleet,
                 batch=batch)
    data, lost_step = _integrate(plan, 0, plan["records"])
    return _dataset(plan, {name: data[:, :, j] for j, name in enumerate(CHANNELS)}, lost_step)


def _plan(records, *, duration, speed, turbulence, failed_rotor, failure_time, failure_level, seed, dt, fs, altitude, span,
          scale_length, intensity_scale, params, gains, fleet, batch, chunk=None) -> dict:
    """The arguments of :func:`simulate_hexacopter` checked, and one entry per record (turbulence, failed rotor,
    failure time, seed and, with a fleet, the drawn aircraft); ``chunk``: the records simulated at once (default
    all)."""
    duration = float_like(duration, "duration", minimum=0.0, strict_min=True)
    if isinstance(speed, (str, bytes)) or np.ndim(speed) > 1 or (np.ndim(speed) == 1 and len(speed) != 2):
        raise ValueError(f"speed must be a number or a (low, high) range in m/s, got {speed!r}")
    if np.ndim(speed) == 0:
        speed = float_like(speed, "speed", minimum=0.0, maximum=MAX_SPEED)
    else:
        speed = tuple(float_like(v, "speed", minimum=0.0, maximum=MAX_SPEED) for v in speed)
        if speed[0] > speed[1]:
            raise ValueError(f"speed: the range (low, high) must have low <= high, got {speed!r}")
    if scale_length is not None:
        scale_length = float_like(scale_length, "scale_length", minimum=0.0, strict_min=True)
    intensity_scale = float_like(intensity_scale, "intensity_scale", minimum=0.0, strict_min=True)
    dt = float_like(dt, "dt", minimum=0.0, strict_min=True)
    fs = float_like(fs, "fs", minimum=0.0, strict_min=True)
    batch = int_like(batch, "batch", minimum=1)
    params = HexacopterParameters() if params is None else params
    gains = ControllerGains() if gains is None else gains
    if not isinstance(params, HexacopterParameters):
        raise TypeError("params must be a HexacopterParameters")
    if not isinstance(gains, ControllerGains):
        raise TypeError("gains must be a ControllerGains")
    if fleet is not None and not isinstance(fleet, FleetSpread):
        raise TypeError(f"fleet must be None or a FleetSpread, got {type(fleet).__name__}")
    q = (1.0 / dt) / fs
    if abs(q - round(q)) > 1e-9 or round(q) < 1:
        raise ValueError(f"fs must divide the integration rate 1/dt = {1 / dt:g} Hz, got fs={fs:g}")
    q = int(round(q))

    def as_list(v):
        if isinstance(v, (str, bytes)) or np.ndim(v) == 0:
            return None
        return list(np.asarray(v).tolist())

    lists = {k: as_list(v) for k, v in
             {"turbulence": turbulence, "failed_rotor": failed_rotor, "failure_time": failure_time,
              "failure_level": failure_level, "seed": seed}.items()}
    lengths = {len(v) for v in lists.values() if v is not None}
    if records is None:
        if len(lengths) > 1:
            raise ValueError(f"turbulence, failed_rotor, failure_time, failure_level and seed have different lengths "
                             f"{lengths}")
        records = lengths.pop() if lengths else 1
    records = int_like(records, "records", minimum=1)
    for k, v in lists.items():
        if v is not None and len(v) != records:
            raise ValueError(f"{k} must have length records={records}, got {len(v)}")

    def per(name, value):
        return lists[name] if lists[name] is not None else [value] * records

    turb = [option("none" if t is None else t, "turbulence", TURBULENCE_LEVELS) for t in per("turbulence", turbulence)]
    rotors = [_rotor_index(r) for r in per("failed_rotor", failed_rotor)]
    ftimes = []
    for r, t in zip(rotors, per("failure_time", failure_time)):
        t = float_like(t, "failure_time", minimum=0.0)
        if r and t >= duration:
            raise ValueError(f"failure_time must be before the end of the record (duration={duration}), got {t}")
        ftimes.append(t if r else np.nan)
    levels = []
    for r, lv in zip(rotors, per("failure_level", failure_level)):
        lv = float_like(lv, "failure_level", minimum=0.0, maximum=1.0, strict_min=True)
        levels.append(lv if r else np.nan)
    seeds = [int_like(s, "seed", minimum=0) for s in per("seed", seed)]

    at_once = records if chunk is None else min(chunk, records)
    if duration / dt * batch * _core.N_OUT > MAX_VALUES or duration * fs * at_once * len(CHANNELS) > MAX_VALUES:
        raise ValueError(f"records={records}, duration={duration:g} s, dt={dt:g} s, fs={fs:g} Hz, batch={batch}: the "
                         f"integration state or the output would hold more than {MAX_VALUES:,} values (2 GiB); "
                         "simulate fewer or shorter records per call")
    n = int(round(duration / dt))
    n -= n % q
    if n < q:
        raise ValueError(f"duration must be at least one output sample (1/fs), got {duration}")
    drawn = None if fleet is None else [fleet.draw(params, sd) for sd in seeds]
    if isinstance(speed, tuple):
        speeds = [float(np.random.default_rng([sd, SPEED_SEED_KEY]).uniform(*speed)) for sd in seeds]
    else:
        speeds = [speed] * records
    return dict(records=records, speed=speed, speeds=speeds, dt=dt, fs=fs, batch=batch, params=params, gains=gains,
                fleet=fleet, q=q, n=n, nout=n // q, turb=turb, rotors=rotors, ftimes=ftimes, levels=levels,
                seeds=seeds, drawn=drawn,
                altitude=altitude, span=span, scale_length=scale_length, intensity_scale=intensity_scale)


def _integrate(plan: dict, first: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
    """Records ``first .. stop - 1`` of ``plan`` integrated and decimated: the output ``(records, nout, channels)``
    and the step of the loss of control of each record (-1: none). A record depends only on its own entries."""
    dt, batch, params, q, n = plan["dt"], plan["batch"], plan["params"], plan["q"], plan["n"]
    altitude, turb, rotors, ftimes, seeds = plan["altitude"], plan["turb"], plan["rotors"], plan["ftimes"], plan["seeds"]
    speeds = plan["speeds"]
    records = stop - first
    # each record's aircraft (its fleet draw, or the one aircraft) trimmed at its own speed; the integrators start at
    # its trim controls
    aircraft = [params] * records if plan["fleet"] is None else [p for p, _ in plan["drawn"][first:stop]]
    trims = {}
    for p, v in zip(aircraft, speeds[first:stop]):
        if (p, v) not in trims:
            trims[(p, v)] = trim(v, params=p, altitude=altitude)
    X0 = np.array([trims[(p, v)]["state"] for p, v in zip(aircraft, speeds[first:stop])])
    I0 = np.array([trims[(p, v)]["integrators"] for p, v in zip(aircraft, speeds[first:stop])])
    P = np.array([p.to_array() for p in aircraft])
    zref = -altitude
    G = plan["gains"].to_array()
    S = np.ascontiguousarray(gain_schedule(params))
    limits = np.array(LOSS_LIMITS)
    samplers = {}
    for i in range(first, stop):
        key = (turb[i], max(speeds[i], 1.0))
        if turb[i] != "none" and key not in samplers:
            samplers[key] = DrydenTurbulence(altitude=altitude, airspeed=key[1], span=plan["span"], intensity=key[0],
                                             scale_length=plan["scale_length"],
                                             intensity_scale=plan["intensity_scale"]).sampler(dt)
    nout = plan["nout"]
    data = np.empty((records, nout, _core.N_OUT))
    lost_step = np.empty(records, dtype=np.int64)
    for start in range(0, records, batch):
        idx = range(first + start, first + min(start + batch, records))
        nb = len(idx)
        gusts = np.zeros((nb, n, 6))
        for j, i in enumerate(idx):
            if turb[i] != "none":
                gusts[j] = draw_gusts(samplers[(turb[i], max(speeds[i], 1.0))], n, check_rng(seeds[i]))
        x0 = X0[start:start + nb]
        i0 = I0[start:start + nb]
        ref = np.array([[speeds[i], 0.0, zref, 0.0] for i in idx])
        fr = np.array([rotors[i] - 1 for i in idx], dtype=np.int64)
        fstep = np.array([int(round(ftimes[i] / dt)) if rotors[i] else -1 for i in idx], dtype=np.int64)
        flevel = np.array([plan["levels"][i] if rotors[i] else 1.0 for i in idx])
        out = np.empty((nb, n, _core.N_OUT))
        lost = np.empty(nb, dtype=np.int64)
        _core.simulate_batch(x0, i0, ref, gusts, P[start:start + nb], G, S, fr, fstep, flevel, n, dt, out, limits,
                             lost)
        del gusts
        if q > 1:
            good = np.nan_to_num(out)
            dec = signal.resample_poly(good, 1, q, axis=1, padtype="line")
            for j in range(nb):
                if lost[j] >= 0:
                    dec[j, lost[j] // q:] = np.nan
        else:
            dec = out
        data[start:start + nb] = dec
        lost_step[start:start + nb] = lost
    return data, lost_step


def _dataset(plan: dict, values: dict, lost_step) -> Any:
    """The Dataset of :func:`simulate_hexacopter` from each channel's ``(record, time)`` values and the loss steps
    (numpy or dask arrays)."""
    import xarray as xr

    records, fs, dt, fleet = plan["records"], plan["fs"], plan["dt"], plan["fleet"]
    rotors, params, gains = plan["rotors"], plan["params"], plan["gains"]
    time = np.arange(plan["nout"]) / fs
    state = ["healthy" if r == 0 else f"rotor{r}" for r in rotors]
    coords = {"record": np.arange(records), "time": ("time", time, {"units": "s"}),
              "state": ("record", state), "turbulence": ("record", plan["turb"]),
              "speed": ("record", np.array(plan["speeds"], dtype=float), {"units": "m/s",
                                                                             "long_name": "commanded speed north"}),
              "seed": ("record", np.array(plan["seeds"], dtype=np.int64)),
              "failure_time": ("record", np.array(plan["ftimes"]), {"units": "s"}),
              "failure_level": ("record", np.array(plan["levels"], dtype=float),
                                {"units": "1", "long_name": "fraction of the failed rotor's effectiveness lost"}),
              "failed_rotor": ("record", np.array(rotors, dtype=np.int64))}
    if fleet is not None:
        for name, (unit, desc) in FLEET_COORDS.items():
            coords[name] = ("record", np.array([v[name] for _, v in plan["drawn"]]),
                            {"units": unit, "long_name": desc})
    vars_ = {name: (("record", "time"), values[name], {"units": unit, "long_name": _DESCRIPTIONS[name]})
             for name, unit in CHANNELS.items()}
    vars_["lost_control"] = ("record", lost_step >= 0)
    vars_["lost_control_time"] = ("record", np.where(lost_step >= 0, lost_step * dt, np.nan), {"units": "s"})
    ds = xr.Dataset(vars_, coords=coords)
    ds.attrs.update({
        "title": "tsfdi hexacopter simulation (Dryden turbulence, rotor failures)",
        "integration": f"RK4, dt={dt} s; decimated to {fs} Hz with scipy.signal.resample_poly (zero phase)",
        "altitude_m": plan["altitude"], "span_m": plan["span"],
        "dryden": (f"MIL-F-8785C low altitude, scale length "
                   f"{'MIL-F-8785C' if plan['scale_length'] is None else repr(plan['scale_length']) + ' m'}, "
                   f"intensities x {plan['intensity_scale']!r}"),
        "scale_length_m": "mil" if plan["scale_length"] is None else plan["scale_length"],
        "intensity_scale": plan["intensity_scale"],
        "rotor_spin": "rotor 1 clockwise seen from above, alternating",
        "parameters": repr(params.to_dict()), "gains": repr(gains.to_dict()),
        "yaw_sign": "positive = nose right (NED)",
    })
    if fleet is not None:
        ds.attrs["fleet"] = repr(fleet.to_dict())
        ds.attrs["fleet_draw"] = (f"uniform per record from numpy.random.default_rng([seed, {FLEET_SEED_KEY:#x}]) "
                                  "around the nominal 'parameters' (tsfdi.datasets.hexacopter.FleetSpread)")
    return ds


def make_hexacopter_dataset(records_per_case: int = 20, *, seed: int = 2024, duration: float = 60.0,
                            failure_time: float = 10.0, speed: float = 5.0,
                            states=STATES, turbulence=("light", "moderate", "severe"),
                            fleet: FleetSpread | None = None, chunks: int | None = None, **kwargs):
    """The benchmark design of the paper's Table 1: states x turbulence levels x ``records_per_case``.

    Record ``k`` (in the order state, turbulence, repetition) gets the seed
    ``numpy.random.SeedSequence([seed, k]).generate_state(1)[0]``, stored in the ``seed`` coordinate, so
    any record can be regenerated alone with :func:`simulate_hexacopter`.

    ``fleet=FleetSpread(...)`` makes a fleet of aircraft of one type (Hansen et al.): each record's mass,
    centre-of-gravity offset, motor constants and inertia are drawn from its seed around the nominal
    parameters (see :class:`FleetSpread`) and stored as record coordinates (:data:`FLEET_COORDS`); the
    turbulence of every record is the same as without it. ``None`` (default): one aircraft, as before.

    ``chunks=n`` returns the data set backed by dask, chunked along ``record`` by ``n`` records, without simulating
    anything: a chunk is simulated when it is computed, on the current dask scheduler, so a fleet of any size can be
    written to zarr or netCDF chunk by chunk (``ds.to_zarr(path)``, ``tsfdi simulate --chunk``) or analysed as it is
    simulated (:mod:`tsfdi.fleet`). Its values are those of ``chunks=None``, bit for bit: a record depends only on its
    seed and configuration. Each computation of a chunk simulates it again: write the fleet once, then open it.
    Other keyword arguments go to :func:`simulate_hexacopter`.
    """
    records_per_case = int_like(records_per_case, "records_per_case", minimum=1)
    seed = int_like(seed, "seed", minimum=0)
    chunks = int_like(chunks, "chunks", minimum=1, optional=True)
    for name, value in (("states", states), ("turbulence", turbulence)):
        if isinstance(value, str) or not len(value):
            raise ValueError(f"{name} must be a non-empty sequence, got {value!r}")
    if records_per_case * len(states) * len(turbulence) > MAX_VALUES:
        raise ValueError(f"records_per_case={records_per_case}: the data set would hold more than {MAX_VALUES:,} values")
    rows = [(s, t) for s in states for t in turbulence for _ in range(records_per_case)]
    rotors = [0 if s == "healthy" else _state_rotor(s) for s, _ in rows]
    seeds = [int(np.random.SeedSequence([seed, k]).generate_state(1)[0]) for k in range(len(rows))]
    design = dict(duration=duration, speed=speed, turbulence=[t for _, t in rows], failed_rotor=rotors,
                  failure_time=failure_time, seed=seeds, fleet=fleet, **kwargs)
    ds = simulate_hexacopter(**design) if chunks is None else _chunked_dataset(design, chunks)
    ds.attrs["base_seed"] = seed
    ds.attrs["records_per_case"] = records_per_case
    return ds


def write_hexacopter_dataset(path: str | os.PathLike, records_per_case: int = 20, *, shipped: bool = False,
                             chunks: int | None = None, scheduler: str = "threads", progress: bool = False,
                             **kwargs: Any) -> Any:
    """Simulate :func:`make_hexacopter_dataset` and write it to a netCDF file or a zarr store (what ``tsfdi
    simulate`` does).

    Parameters
    ----------
    path : str or path-like
        A netCDF file, or a zarr store (format 2) for a name ending in ``.zarr`` (that needs ``chunks``).
    records_per_case : int
        Records per state and turbulence level.
    shipped : bool
        Write only :data:`SHIPPED_VARIABLES` packed as int32 counts (:func:`encode_for_file`, the format of the
        shipped ``data/hexacopter.nc``); default every channel as float64 (zlib and shuffle).
    chunks : int, optional
        Records per chunk: the chunks are simulated in parallel on ``scheduler`` and written as they come
        (:func:`tsfdi.fleet.write_fleet`, needs dask), so memory holds a few chunks whatever the number of records.
        Default ``None``: the records are simulated in memory and written to a netCDF file.
    scheduler : str
        With ``chunks``: ``"threads"``, ``"processes"`` (zarr only), ``"synchronous"`` or the address of a
        ``dask.distributed`` scheduler (:func:`tsfdi.fleet.dask_scheduler`).
    progress : bool
        With ``chunks``: show a progress bar.
    **kwargs
        The design of :func:`make_hexacopter_dataset` (``seed``, ``duration``, ``failure_time``, ``states``,
        ``turbulence``, ``fleet``, ...) and :func:`simulate_hexacopter`'s options (``dt``, ``fs``).

    Returns
    -------
    xarray.Dataset
        What the file holds per record, read back into memory: the record coordinates (state, turbulence,
        failure time, seed, the fleet's draws) and ``lost_control`` / ``lost_control_time``.

    Examples
    --------
    >>> written = write_hexacopter_dataset("flights.nc", 2, duration=10.0, states=("healthy", "rotor1"),
    ...                                    turbulence=("light",))                    # doctest: +SKIP
    >>> int(written["lost_control"].sum())                                          # doctest: +SKIP
    0
    """
    import xarray as xr

    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a file name (str or path-like), got {type(path).__name__}")
    shipped = boolean(shipped, "shipped")
    zarr = os.fspath(path).lower().endswith(".zarr")
    if zarr and chunks is None:
        raise ValueError(f"chunks: {os.fspath(path)} is a zarr store, written chunk by chunk on dask: give chunks "
                         "(records per chunk)")
    ds = make_hexacopter_dataset(records_per_case, chunks=chunks, **kwargs)
    if shipped:
        ds, enc = encode_for_file(ds)
    else:
        enc = {v: {"zlib": True, "shuffle": True} for v in ds.data_vars}
    if chunks is None:
        ds.to_netcdf(path, engine="h5netcdf", encoding=enc)
    else:
        from tsfdi.fleet import write_fleet

        write_fleet(ds, path, encoding=enc, scheduler=scheduler, progress=progress)
    with xr.open_zarr(path) if zarr else xr.open_dataset(path, engine="h5netcdf") as written:
        return written.drop_dims("time").load()


def _chunked_dataset(design: dict, chunks: int) -> Any:
    """:func:`simulate_hexacopter` of ``design`` as a Dataset backed by dask, one delayed simulation per ``chunks``
    records."""
    import dask
    import dask.array as da

    parameters = inspect.signature(simulate_hexacopter).parameters
    unknown = sorted(set(design) - set(parameters))
    if unknown:
        raise TypeError(f"make_hexacopter_dataset got unexpected keyword argument(s) {unknown}")
    plan = _plan(**{**{k: p.default for k, p in parameters.items()}, **design}, chunk=chunks)
    nout, nchan = plan["nout"], len(CHANNELS)
    outputs, losses = [], []
    for first in range(0, plan["records"], chunks):
        stop = min(first + chunks, plan["records"])
        # each chunk carries the entries of its own records only
        sub = {**plan, **{k: plan[k][first:stop] for k in ("turb", "rotors", "ftimes", "levels", "seeds", "speeds")},
               "drawn": None if plan["drawn"] is None else plan["drawn"][first:stop]}
        part = dask.delayed(_integrate, nout=2)(sub, 0, stop - first)
        outputs.append(da.from_delayed(part[0], (stop - first, nout, nchan), dtype=np.float64))
        losses.append(da.from_delayed(part[1], (stop - first,), dtype=np.int64))
    data = da.concatenate(outputs)
    return _dataset(plan, {name: data[:, :, j] for j, name in enumerate(CHANNELS)}, da.concatenate(losses))


def _state_rotor(state: str) -> int:
    if not isinstance(state, str) or not state.startswith("rotor"):
        raise ValueError(f"states must be 'healthy' or 'rotor<k>', got {state!r}")
    return _rotor_index(int(state[5:]))


#: Packing of the shipped file: int32 counts of these steps (units of the variable per count), zlib + shuffle.
#: The smallest one-step prediction error (AR(10) residual standard deviation) of each variable over the
#: healthy light-turbulence records of the shipped design (the blade-element aircraft, seed 2024) is roll
#: 2.3e-5 rad, pitch 1.1e-5 rad, yaw 6.4e-6 rad, r 7.3e-4 rad/s, collective 0.05, roll/pitch control 0.28 / 0.14,
#: yaw control 0.076 rad/s. The attitude and yaw-rate steps are below 1/20 of it (rounding, standard deviation
#: step/sqrt(12), adds < 0.03 % to the residual variance), the control steps below 1/10 (< 0.1 %). Tested in
#: ``tests/datasets/test_hexacopter.py::test_packing_step_far_below_ar_residual``. The heading step 2e-7 rad
#: holds headings up to 429 rad (68 turns: a failed one-way-rotor aircraft may spin in stronger turbulence; the
#: shipped records stay within 0.73 rad); a larger one raises ``ValueError`` when the file is written. The body
#: rates p, q (and the other channels) are in every file written without ``--shipped``; in the shipped file they
#: would pass the 20 MB budget.
PACK_SCALE = {"roll": 1e-6, "pitch": 5e-7, "yaw": 2e-7, "p": 5e-5, "q": 5e-5, "r": 1e-6,
              "collective": 2e-3, "roll_control": 1e-2, "pitch_control": 1e-2, "yaw_control": 1e-4}
#: Variables of the shipped file: the paper's attitude signals, the yaw rate and the four controls of eq. 2.
#: Channels of :func:`hexacopter_signals` with ``yaw="rate"`` (the default): roll, pitch and the body yaw rate.
SIGNAL_CHANNELS = ("roll", "pitch", "yaw_rate")

SHIPPED_VARIABLES = ("roll", "pitch", "yaw", "r", "collective", "roll_control", "pitch_control", "yaw_control")
_INT32_FILL = -2147483648


def encode_for_file(ds, variables=SHIPPED_VARIABLES):
    """Keep ``variables`` and return ``(dataset, encoding)`` for a compact netCDF (int32 + zlib + shuffle).

    Values are stored as ``round(x / scale)`` (NaN as -2**31); the decoded value differs from the
    simulated one by at most ``scale / 2`` (:data:`PACK_SCALE`). Out-of-range values raise ``ValueError``.
    """
    keep = list(variables) + ["lost_control", "lost_control_time"]
    out = ds[keep]
    enc = {}
    for v in variables:
        s = PACK_SCALE[v]
        if out[v].chunks is not None:           # backed by dask: each chunk is checked when it is computed
            out[v] = out[v].copy(data=out[v].data.map_blocks(_int32_range, v, s, dtype=out[v].dtype))
        else:
            _int32_range(out[v].values, v, s)
        # chunks of 20 records compress ~10 % better than one record per chunk (zlib sees more context)
        enc[v] = {"dtype": "int32", "scale_factor": s, "_FillValue": _INT32_FILL, "zlib": True, "complevel": 9,
                  "shuffle": True, "chunksizes": (min(20, out.sizes["record"]), out.sizes["time"])}
    return out, enc


def _int32_range(x: np.ndarray, name: str, scale: float) -> np.ndarray:
    """``x`` if ``round(x / scale)`` fits in int32 (:func:`encode_for_file`), else a ``ValueError`` naming ``name``."""
    m = np.nanmax(np.abs(x)) / scale if np.isfinite(x).any() else 0
    if m > 2.1e9:
        raise ValueError(f"{name} exceeds the int32 range with scale_factor {scale} (max |x| = {m * scale:g})")
    return x


def hexacopter_signals(data: Any, *, yaw: str = "rate") -> Any:
    """Roll, pitch and yaw channels of a hexacopter dataset as one ``(record, time, channel)`` DataArray.

    Parameters
    ----------
    data : xarray.Dataset
        As returned by :func:`tsfdi.datasets.load_hexacopter` (variables ``roll``, ``pitch``, ``yaw``).
    yaw : {"rate", "angle"}
        ``"rate"`` (default): the body yaw rate, channel ``yaw_rate``: the dataset's ``r`` variable when it has
        one, else the heading increment times ``fs`` (the first sample is then dropped so every channel has the
        same time axis). The heading is the integral of the yaw rate under a slow heading loop (time constant
        1 / k_heading, about 3 s), so at 100 Hz it is close to a unit-root process and an AR/VAR of order 20
        does not whiten it; with the regular aircraft it also slips by whole turns in severe turbulence.
        ``"angle"``: the raw heading.

    Returns
    -------
    xarray.DataArray
        Dims ``(record, time, channel)`` with the dataset's record coordinates; backed by dask, not read, when the
        dataset's variables are.
    """
    import xarray as xr

    if not isinstance(data, xr.Dataset):
        raise TypeError(f"data must be an xarray.Dataset with roll, pitch and yaw variables, got "
                        f"{type(data).__name__}")
    yaw = option(yaw, "yaw", ("rate", "angle"))
    use_r = yaw == "rate" and "r" in data
    missing = [v for v in ("roll", "pitch", "r" if use_r else "yaw") if v not in data]
    if missing:
        raise ValueError(f"data lacks the variable(s) {missing}")
    t = np.asarray(data["time"].values, dtype=float)
    fs = 1.0 / float(np.median(np.diff(t)))
    # numpy arrays, or dask arrays left lazy (a fleet read chunk by chunk where it is used: tsfdi.fleet)
    arrs = [data[v].transpose("record", "time").data.astype(np.float64, copy=False)
            for v in ("roll", "pitch", "r" if use_r else "yaw")]
    if use_r:
        names = list(SIGNAL_CHANNELS)
    elif yaw == "rate":
        arrs = [a[:, 1:] for a in arrs[:2]] + [np.diff(arrs[2], axis=1) * fs]
        t = t[1:]
        names = list(SIGNAL_CHANNELS)
    else:
        names = ["roll", "pitch", "yaw"]
    vals = np.stack(arrs, axis=-1)
    # the per-record labels read here, together, by dask's threads when dask backs them (a store opened in this
    # process: xarray has read its metadata here): a fleet's labels come in one small array per label and chunk of
    # records, hundreds of tasks that would cost a dask.distributed cluster ~1 s per call for a few kB
    keys = [k for k, c in data.coords.items() if c.dims == ("record",) and k != "record"]
    labels = xr.Dataset({k: data[k].variable for k in [*keys, "lost_control"] if k in data})
    labels = labels.compute(scheduler="threads")
    coords = {k: (("record",), np.asarray(labels[k].values)) for k in keys}
    coords["record"] = np.asarray(data["record"].values)
    coords["time"] = t
    coords["channel"] = names
    if "lost_control" in data:
        coords["lost_control"] = (("record",), np.asarray(labels["lost_control"].values, dtype=bool))
    return xr.DataArray(vals, dims=("record", "time", "channel"), coords=coords, name="attitude")
