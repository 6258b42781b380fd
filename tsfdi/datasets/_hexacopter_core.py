"""Numba-compiled kernels of the hexacopter simulator (one record per call, no Python objects).

The equations are documented in :mod:`tsfdi.datasets.hexacopter`. The parameter and gain vectors are
``HexacopterParameters.to_array()`` and ``ControllerGains.to_array()`` (field order of those dataclasses in
:mod:`tsfdi.datasets._hexacopter_params`). Each record is integrated independently, in scalar code, so a record's result does not
depend on which other records are simulated with it (bit-for-bit regeneration of subsets).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

# output channels at the integration rate: 12 states, 7 controls, specific force (3), rotor speeds (6), motor
# commands (6)
N_OUT = 34
N_X = 24  # 12 rigid-body states + 6 rotor speeds + 6 induced velocities (blade-element rotors only)
# yaw-rate integrator runs only while at least this fraction of the yaw term reaches the rotors
YAW_FREEZE = 0.75


@njit(cache=True)
def dryden_recursion(Ad, F, C, x0, e):
    n = e.shape[0]
    ns = Ad.shape[0]
    no = C.shape[0]
    out = np.empty((n, no))
    x = x0.copy()
    xn = np.empty(ns)
    for k in range(n):
        for j in range(no):
            s = 0.0
            for m in range(ns):
                s += C[j, m] * x[m]
            out[k, j] = s
        for i in range(ns):
            s = 0.0
            for m in range(ns):
                s += Ad[i, m] * x[m] + F[i, m] * e[k, m]
            xn[i] = s
        for i in range(ns):
            x[i] = xn[i]
    return out


@njit(cache=True)
def _ned_velocity(x):
    phi = x[3]
    th = x[4]
    psi = x[5]
    u = x[6]
    v = x[7]
    w = x[8]
    sph = math.sin(phi)
    cph = math.cos(phi)
    sth = math.sin(th)
    cth = math.cos(th)
    sps = math.sin(psi)
    cps = math.cos(psi)
    vn = cth * cps * u + (sph * sth * cps - cph * sps) * v + (cph * sth * cps + sph * sps) * w
    ve = cth * sps * u + (sph * sth * sps + cph * cps) * v + (cph * sth * sps - sph * cps) * w
    vd = -sth * u + sph * cth * v + cph * cth * w
    return vn, ve, vd


@njit(cache=True)
def _bet(P, om, vhx, vhy, vhz, vi, e, load):
    """Blade-element loads of one fixed-pitch rotor (closed form, uniform inflow) and its inflow rate.

    ``om`` rotor speed relative to the air (rad/s, >= 0), ``(vhx, vhy, vhz)`` hub velocity relative to the air
    in body axes, ``vi`` induced velocity (m/s, down through the disc), ``e`` the rotor's effectiveness (1:
    healthy; every load is multiplied by it and the wake is driven by the reduced thrust; a factor 1.0 leaves the
    loads bit for bit). ``load`` out: thrust T (N, along -z),
    torque Q (N m, absorbed), in-plane force per unit in-plane hub velocity (H = -h (vhx, vhy)), rolling
    moment per unit in-plane hub velocity (m_R, times the spin sign), pitching moment per unit in-plane hub
    velocity (m_P), d vi / dt.
    """
    rho = P[14]
    nb = P[22]
    R = P[23]
    c = P[24]
    a = P[25]
    th0 = P[26]
    thtw = P[27]
    cd0 = P[28]
    k = rho * nb * c * R          # rho A sigma
    vt = om * R                   # tip speed
    vh2 = vhx * vhx + vhy * vhy
    vn = vi - vhz                 # flow down through the disc
    T = e * (k * 0.5 * a * (th0 * (vt * vt / 3.0 + vh2 / 2.0) + thtw * (vt * vt + vh2) / 4.0 - vn * vt / 2.0))
    Q = e * (k * R * (0.5 * a * vn * (th0 * vt / 3.0 + thtw * vt / 4.0 - vn / 2.0) + cd0 * (vt * vt + vh2) / 8.0))
    h = e * (k * (0.25 * a * vn * (th0 / 2.0 + thtw / 3.0) + cd0 * vt / 4.0))
    mr = e * (k * R * 0.5 * a * (th0 * vt / 3.0 + thtw * vt / 4.0 - vn / 4.0))
    vm = math.sqrt(vh2 + vn * vn)
    vpos = vn if vn > 0.0 else 0.0
    # longitudinal inflow gradient kx = 15 pi / 32 tan(chi / 2) (Pitt & Peters), tan(chi / 2) = V_h / (V + V_n)
    mp = 0.0
    if vm + vpos > 0.0:
        mp = e * (k * R * a * vi * vt * (15.0 * math.pi / 32.0) / (16.0 * (vm + vpos)))
    load[0] = T
    load[1] = Q
    load[2] = h
    load[3] = mr
    load[4] = mp
    load[5] = _inflow_rate(P, T, vm, vi)


@njit(cache=True)
def _inflow_rate(P, T, vm, vi):
    """d vi / dt of the Pitt-Peters uniform mode, (8/3) rho R^3 dvi/dt = T - 2 rho pi R^2 V_m vi (``vm`` the mass-flow
    velocity through the disc)."""
    rho = P[14]
    R = P[23]
    return (T - 2.0 * rho * math.pi * R * R * vm * vi) / (8.0 / 3.0 * rho * R * R * R)


@njit(cache=True)
def _bet_rotors(x, P, eff, ur, vr, wr, pr, qr, rr, dx):
    """Forces and moments of the six blade-element rotors about the centre of gravity (body axes); writes the
    inflow rates ``dx[18:24]``. ``eff``: effectiveness of each rotor (1 healthy, 0 failed)."""
    arm = P[5]
    hr = P[6]
    ch = P[11]
    kf = P[12]
    cgx = P[19]
    cgy = P[20]
    load = np.empty(6)
    Fx = 0.0
    Fy = 0.0
    Fz = 0.0
    Mx = 0.0
    My = 0.0
    Mz = 0.0
    for i in range(6):
        ang = i * (math.pi / 3.0)
        xi = arm * math.cos(ang) - cgx
        yi = arm * math.sin(ang) - cgy
        zi = -hr
        spin = 1.0 if i % 2 == 0 else -1.0
        # one-way rotor: the speed relative to the air (motor speed plus the body's yaw rate relative to the air)
        om = x[12 + i]
        if om < 0.0:
            om = 0.0
        om = om + spin * rr
        if om < 0.0:
            om = 0.0
        vhx = ur + qr * zi - rr * yi
        vhy = vr + rr * xi - pr * zi
        vhz = wr + pr * yi - qr * xi
        vi = x[18 + i]
        e = eff[i]
        if e == 0.0:
            # a failed rotor makes no load; its wake decays (Pitt-Peters with T = 0)
            dx[18 + i] = _inflow_rate(P, 0.0, math.sqrt(vhx * vhx + vhy * vhy + (vi - vhz) ** 2), vi)
            continue
        _bet(P, om, vhx, vhy, vhz, vi, e, load)
        dx[18 + i] = load[5]
        T = load[0]
        # in-plane force: blade-element H-force plus the optional lumped rotor drag (blade flexibility)
        hh = load[2] + e * ch * om
        fx = -hh * vhx
        fy = -hh * vhy
        fz = -T
        Fx += fx
        Fy += fy
        Fz += fz
        Mx += yi * fz - zi * fy
        My += zi * fx - xi * fz
        Mz += xi * fy - yi * fx
        # hub moments: rolling moment of the advancing blade (towards the retreating side: spin-dependent)
        # and pitching moment of the longitudinal inflow gradient plus the optional lumped flapping term
        mp = load[4] + e * kf * om
        Mx += spin * load[3] * vhx - mp * vhy
        My += spin * load[3] * vhy + mp * vhx
        Mz += -spin * load[1]
    return Fx, Fy, Fz, Mx, My, Mz


@njit(cache=True)
def _lumped_rotors(x, P, eff, ur, vr, wr, pr, qr, rr):
    """Forces and moments of the six lumped-coefficient rotors (``blade_element=False``: thrust and torque
    coefficients, inflow, rotor drag and flapping terms) about the centre of gravity (body axes); every load of
    rotor ``i`` times its effectiveness ``eff[i]`` (1 healthy, 0 failed)."""
    arm = P[5]
    hr = P[6]
    kT = P[7]
    kQ = P[8]
    cw = P[10]
    ch = P[11]
    kf = P[12]
    rev = P[18] > 0.0
    # centre-of-gravity offset from the hub centre (body x, y): the rotor arms are measured from the CG
    cgx = P[19]
    cgy = P[20]
    Fx = 0.0
    Fy = 0.0
    Fz = 0.0
    Mx = 0.0
    My = 0.0
    Mz = 0.0
    for i in range(6):
        ang = i * (math.pi / 3.0)
        xi = arm * math.cos(ang) - cgx
        yi = arm * math.sin(ang) - cgy
        zi = -hr
        om = x[12 + i]
        if om < 0.0 and not rev:
            om = 0.0
        e = eff[i]
        if e == 0.0:
            continue
        # rotor speed relative to the air: the motor holds om relative to the airframe, which turns at
        # r - r_g relative to the air (rotor 1 clockwise seen from above, directions alternating)
        spin = 1.0 if i % 2 == 0 else -1.0
        om = om + spin * rr
        if om < 0.0 and not rev:
            om = 0.0
        aom = abs(om)
        # hub velocity relative to air: v_rel + omega_rel x r_i
        vhx = ur + qr * zi - rr * yi
        vhy = vr + rr * xi - pr * zi
        vhz = wr + pr * yi - qr * xi
        T = e * kT * om * aom + e * cw * aom * vhz
        if T < 0.0 and not rev:
            T = 0.0
        fx = -(e * ch) * aom * vhx
        fy = -(e * ch) * aom * vhy
        fz = -T
        Fx += fx
        Fy += fy
        Fz += fz
        # r_i x F_i
        Mx += yi * fz - zi * fy
        My += zi * fx - xi * fz
        Mz += xi * fy - yi * fx
        # blade-flapping moment: disc tilts away from the relative wind
        Mx += -(e * kf) * aom * vhy
        My += e * kf * aom * vhx
        # reaction torque, opposite to the rotor's spin (yaw damping -2 k_Q om r through om)
        Mz += -spin * (e * kQ) * om * aom
    return Fx, Fy, Fz, Mx, My, Mz


@njit(cache=True)
def _deriv(x, wcmd, g, P, eff, dx, sf):
    # parameters
    m = P[0]
    grav = P[1]
    Ixx = P[2]
    Iyy = P[3]
    Izz = P[4]
    tau = P[9]
    cda = P[13]
    rho = P[14]
    kn = P[15]
    phi = x[3]
    th = x[4]
    u = x[6]
    v = x[7]
    w = x[8]
    p = x[9]
    q = x[10]
    r = x[11]
    sph = math.sin(phi)
    cph = math.cos(phi)
    sth = math.sin(th)
    cth = math.cos(th)
    ur = u - g[0]
    vr = v - g[1]
    wr = w - g[2]
    pr = p - g[3]
    qr = q - g[4]
    rr = r - g[5]
    if P[21] > 0.0:
        Fx, Fy, Fz, Mx, My, Mz = _bet_rotors(x, P, eff, ur, vr, wr, pr, qr, rr, dx)
    else:
        Fx, Fy, Fz, Mx, My, Mz = _lumped_rotors(x, P, eff, ur, vr, wr, pr, qr, rr)
        for i in range(6):
            dx[18 + i] = 0.0        # no inflow states
    # fuselage drag and weathervane yaw moment
    vmag = math.sqrt(ur * ur + vr * vr + wr * wr)
    Fx += -0.5 * rho * cda * vmag * ur
    Fy += -0.5 * rho * cda * vmag * vr
    Fz += -0.5 * rho * cda * vmag * wr
    vh = math.sqrt(ur * ur + vr * vr)
    Mz += kn * vh * vr
    # specific force (what an accelerometer at the centre of gravity measures), body axes
    sf[0] = Fx / m
    sf[1] = Fy / m
    sf[2] = Fz / m
    # gravity in body axes
    Fx += -m * grav * sth
    Fy += m * grav * sph * cth
    Fz += m * grav * cph * cth
    # translational: m (vdot + omega x v) = F
    dx[6] = Fx / m - (q * w - r * v)
    dx[7] = Fy / m - (r * u - p * w)
    dx[8] = Fz / m - (p * v - q * u)
    # rotational (principal axes)
    dx[9] = (Mx - (Izz - Iyy) * q * r) / Ixx
    dx[10] = (My - (Ixx - Izz) * p * r) / Iyy
    dx[11] = (Mz - (Iyy - Ixx) * p * q) / Izz
    # Euler angle rates (Z-Y-X)
    tth = sth / cth
    dx[3] = p + (q * sph + r * cph) * tth
    dx[4] = q * cph - r * sph
    dx[5] = (q * sph + r * cph) / cth
    # position: NED velocity = R v
    dx[0], dx[1], dx[2] = _ned_velocity(x)
    for i in range(6):
        dx[12 + i] = (wcmd[i] - x[12 + i]) / tau


@njit(cache=True)
def _schedule(S, speed, out):
    """Gain factors ``out`` = (altitude, roll, pitch, yaw) at ground speed ``speed``: linear interpolation in the
    rows ``[speed, f_altitude, f_roll, f_pitch, f_yaw]`` of ``S`` (speeds increasing), constant beyond the ends."""
    n = S.shape[0]
    if n == 1 or speed <= S[0, 0]:
        for j in range(4):
            out[j] = S[0, 1 + j]
        return
    if speed >= S[n - 1, 0]:
        for j in range(4):
            out[j] = S[n - 1, 1 + j]
        return
    i = 0
    while S[i + 1, 0] < speed:
        i += 1
    w = (speed - S[i, 0]) / (S[i + 1, 0] - S[i, 0])
    for j in range(4):
        out[j] = S[i, 1 + j] + w * (S[i + 1, 1 + j] - S[i, 1 + j])


@njit(cache=True)
def _controller(x, integ, ref, G, P, S, ctrl, wcmd):
    """Cascade of Fig. 2: velocity -> attitude commands -> attitude/altitude loops -> mixer.

    integ: [I_theta, I_phi, I_collective, I_roll, I_pitch, I_yaw]; ref: [vn_c, ve_c, Z_c, psi_c];
    S: gain schedule over the ground speed (:func:`_schedule`; one row of ones: the fixed hover design);
    ctrl out: [Om0, OmR, OmP, OmY, phi_c, theta_c, psi_c] (+ integrator rates in ctrl[7:12]).
    """
    vn, ve, vd = _ned_velocity(x)
    f = np.empty(4)
    _schedule(S, math.sqrt(vn * vn + ve * ve), f)
    # scheduled gains: each gain times the factor of its loop (a factor 1.0 leaves the gain bit for bit)
    kv, kvi, kz, kzd, kzi, katt, krate, katti, kpsi, kr, maxtilt = (
        G[0], G[1], G[2] * f[0], G[3] * f[0], G[4] * f[0], G[5], G[6], G[7], G[8], G[9] * f[3], G[10])
    katt_r = katt * f[1]
    krate_r = krate * f[1]
    katti_r = katti * f[1]
    katt_p = katt * f[2]
    krate_p = krate * f[2]
    katti_p = katti * f[2]
    kyi = G[12] * f[3]
    wmin = P[16]
    wmax = P[17]
    psi = x[5]
    c = math.cos(psi)
    s = math.sin(psi)
    # velocity loop in the world (north-east) frame: tilt commands toward north (a_n, pitch-like) and
    # east (a_e, roll-like) with integrators in the world frame, limited in magnitude to max_tilt, then
    # rotated into the heading frame each step (correct also while the aircraft turns)
    en = ref[0] - vn
    ee = ref[1] - ve
    a_n = integ[0] - kv * en
    a_e = integ[1] + kv * ee
    tilt = math.sqrt(a_n * a_n + a_e * a_e)
    sat = tilt > maxtilt
    if sat:
        a_n *= maxtilt / tilt
        a_e *= maxtilt / tilt
    th_c = c * a_n - s * a_e
    ph_c = s * a_n + c * a_e
    ez = x[2] - ref[2]
    om0 = integ[2] + kz * ez + kzd * vd
    e_ph = ph_c - x[3]
    e_th = th_c - x[4]
    omr = integ[3] + katt_r * e_ph - krate_r * x[9]
    omp = integ[4] + katt_p * e_th - krate_p * x[10]
    # heading error wrapped to (-pi, pi]: after a turn the loop aims at the nearest equivalent heading
    e_psi = ref[3] - psi
    e_psi -= 2.0 * math.pi * math.floor((e_psi + math.pi) / (2.0 * math.pi))
    if e_psi > math.pi:
        e_psi -= 2.0 * math.pi
    elif e_psi <= -math.pi:
        e_psi += 2.0 * math.pi
    rc = kpsi * e_psi
    if rc > G[11]:
        rc = G[11]
    elif rc < -G[11]:
        rc = -G[11]
    e_r = rc - x[11]
    omy = integ[5] + kr * e_r
    # attitude priority: the yaw-control limit shrinks linearly to zero as the roll + pitch error grows
    # to ``yaw_priority_error`` (a yaw term can then never take the authority the attitude loops need)
    ylim = G[13] * (1.0 - (abs(e_ph) + abs(e_th)) / G[14])
    if ylim < 0.0:
        ylim = 0.0
    yclip = 0
    if omy > ylim:
        omy = ylim
        yclip = 1
    elif omy < -ylim:
        omy = -ylim
        yclip = -1
    # fixed mixer, thrust-linear and saturation-aware. The four controls are rotor-speed deviations (rad/s,
    # eq. 2) about the collective speed Omega_0; they are mixed in thrust (Omega^2), linearised at Omega_0,
    #     Omega_c,i^2 = Omega_0^2 + 2 Omega_0 (-sin(psi_i) Omega_R + cos(psi_i) Omega_P -/+ Omega_Y),
    # so that a control changes the thrust and torque of every rotor by the same amount whatever its speed
    # (the thrust linearisation of flight-control firmware; near Omega_0 it is eq. 2). A rotor running
    # slow -- the one opposite a failed rotor -- then does not lose its share of the moments. Collective,
    # roll and pitch are clipped to the speed limits first; the yaw term is then added to each rotor and
    # clipped to what that rotor has left. A rotor near a limit (or a dead rotor whose command the
    # pitch/roll loops drive up) delivers less of the yaw term while the others keep theirs; the yaw-rate
    # integrator freezes while less than ``yaw_freeze`` of the commanded yaw term reaches the rotors
    # (anti-windup).
    hi = wmax * wmax
    # signed squared speeds: a reversible rotor may be commanded down to -omega_max
    lo = -hi if P[18] > 0.0 else wmin * wmin
    # one-way rotors: a negative collective asks for the least thrust, not (through its square) for full thrust
    if P[18] <= 0.0 and om0 < 0.0:
        om0 = 0.0
    two_om0 = 2.0 * om0
    asked = 0.0
    given = 0.0
    for i in range(6):
        ang = i * (math.pi / 3.0)
        b2 = om0 * om0 + two_om0 * (-math.sin(ang) * omr + math.cos(ang) * omp)
        if b2 < lo:
            b2 = lo
        elif b2 > hi:
            b2 = hi
        my = -1.0 if i % 2 == 0 else 1.0
        c2 = b2 + two_om0 * my * omy
        if c2 < lo:
            c2 = lo
        elif c2 > hi:
            c2 = hi
        wcmd[i] = math.sqrt(c2) if c2 >= 0.0 else -math.sqrt(-c2)
        asked += abs(omy)
        if om0 > 0.0:
            given += abs(c2 - b2) / two_om0
    alpha = given / asked if asked > 0.0 else 1.0
    ctrl[0] = om0
    ctrl[1] = omr
    ctrl[2] = omp
    ctrl[3] = omy
    ctrl[4] = ph_c
    ctrl[5] = th_c
    ctrl[6] = ref[3]
    # integrator rates (anti-windup: freeze tilt integrators while the tilt command saturates)
    ctrl[7] = -kvi * en if not sat else 0.0
    ctrl[8] = kvi * ee if not sat else 0.0
    ctrl[9] = kzi * ez
    ctrl[10] = katti_r * e_ph
    ctrl[11] = katti_p * e_th
    # yaw-rate integrator: runs while the yaw term reaches the rotors and is not limited; while it is
    # limited (or the rotors cannot deliver it) only unwinding is allowed (anti-windup)
    di = kyi * e_r
    if (alpha < YAW_FREEZE or yclip != 0) and di * integ[5] > 0.0:
        di = 0.0
    ctrl[12] = di


@njit(cache=True)
def simulate_record(x0, integ0, ref, gust, P, G, S, fail_rotor, fail_step, fail_level, n_steps, dt, out, limits):
    """Integrate one record with RK4 at step ``dt``; write ``N_OUT`` channels per step into ``out``: the 12
    rigid-body states, the 7 controller outputs, the specific force (from the first RK4 stage, the state and
    commands of the step), the 6 rotor speeds and the 6 motor commands.

    ``fail_rotor`` is 0-based (-1: none); from ``fail_step`` on it keeps ``1 - fail_level`` of its loads
    (``fail_level`` 1.0: the rotor makes none, an abrupt loss). Returns the step at which control was lost (-1: never).
    ``limits``: [max |roll|, max |pitch| (rad), max altitude error (m)]; ground contact (z > 0) is a loss too.
    """
    x = x0.copy()
    integ = integ0.copy()
    eff = np.ones(6)
    k1 = np.empty(N_X)
    k2 = np.empty(N_X)
    k3 = np.empty(N_X)
    k4 = np.empty(N_X)
    xt = np.empty(N_X)
    ctrl = np.empty(13)
    wcmd = np.empty(6)
    g = np.empty(6)
    sf = np.empty(3)
    lost = -1
    for k in range(n_steps):
        if k == fail_step and fail_rotor >= 0:
            eff[fail_rotor] = 1.0 - fail_level
        if lost >= 0:
            for j in range(N_OUT):
                out[k, j] = np.nan
            continue
        _controller(x, integ, ref, G, P, S, ctrl, wcmd)
        for j in range(12):
            out[k, j] = x[j]
        for j in range(7):
            out[k, 12 + j] = ctrl[j]
        for j in range(6):
            g[j] = gust[k, j]
        _deriv(x, wcmd, g, P, eff, k1, sf)
        for j in range(3):
            out[k, 19 + j] = sf[j]
        for j in range(6):
            out[k, 22 + j] = x[12 + j]
            out[k, 28 + j] = wcmd[j]
        for j in range(N_X):
            xt[j] = x[j] + 0.5 * dt * k1[j]
        _deriv(xt, wcmd, g, P, eff, k2, sf)
        for j in range(N_X):
            xt[j] = x[j] + 0.5 * dt * k2[j]
        _deriv(xt, wcmd, g, P, eff, k3, sf)
        for j in range(N_X):
            xt[j] = x[j] + dt * k3[j]
        _deriv(xt, wcmd, g, P, eff, k4, sf)
        for j in range(N_X):
            x[j] = x[j] + dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
        for j in range(6):
            integ[j] += dt * ctrl[7 + j]
        bad = False
        for j in range(N_X):
            if not math.isfinite(x[j]):
                bad = True
        # lost: non-finite state, roll or pitch beyond the limits, altitude error beyond the limit, or
        # ground contact (z is down: altitude -z below 0)
        if (bad or abs(x[3]) > limits[0] or abs(x[4]) > limits[1] or abs(x[2] - ref[2]) > limits[2]
                or x[2] > 0.0):
            lost = k + 1
    return lost


@njit(cache=True, parallel=True)
def simulate_batch(x0, integ0, ref, gusts, P, G, S, fail_rotor, fail_step, fail_level, n_steps, dt, out, limits,
                   lost):
    """Records in parallel; ``P`` holds one parameter vector per record (rows), ``G`` and the schedule ``S``
    are shared."""
    for i in prange(x0.shape[0]):
        lost[i] = simulate_record(x0[i], integ0[i], ref[i], gusts[i], P[i], G, S, fail_rotor[i], fail_step[i],
                                  fail_level[i], n_steps, dt, out[i], limits)


@njit(cache=True)
def derivative(x, wcmd, g, P, eff):
    dx = np.empty(N_X)
    sf = np.empty(3)
    _deriv(x, wcmd, g, P, eff, dx, sf)
    return dx


@njit(cache=True)
def controller(x, integ, ref, G, P, S):
    ctrl = np.empty(13)
    wcmd = np.empty(6)
    _controller(x, integ, ref, G, P, S, ctrl, wcmd)
    return ctrl, wcmd
