r"""The sensors an autopilot logs, simulated from a hexacopter's true 1 kHz trajectory.

:func:`sensor_log` turns one record of ``simulate_hexacopter(..., fs=1000)`` into the topics a flight log holds,
each at its own rate with the noise, bias, range and resolution of a common part, and :func:`write_sensor_log`
writes them as a folder of per-topic CSV files that :func:`tsfdi.read_records` reads as it reads a real log.
:class:`SensorSuite` holds the parts' parameters; every default is cited in its docstring (datasheet name and
number) or said to be a typical-part choice.

Notes
-----
**Sampling.** Every topic is stamped on multiples of its own period :math:`T = 1/f`, counted from the record's
first sample; sample :math:`k = 1, 2, \dots` of a topic is stamped :math:`t_0 + kT`. :math:`f` must divide the
1 kHz of the simulation, so that a period is :math:`n = 1000/f` simulation steps.

- *Gyroscope, accelerometer, barometer* (integrating sensors): the output at :math:`t_k` is the mean of the
  :math:`n` true 1 kHz samples in :math:`(t_k - T, t_k]` (the boxcar of an integrating ADC or of a driver that
  averages a FIFO; anti-alias: a boxcar of length :math:`T` has its first zero at :math:`f`), plus the part's
  errors. It is causal: the stamp is the end of the interval.
- *GPS*: the true velocity and position at :math:`t_k - \tau` (latency :math:`\tau`), plus the receiver's
  errors; the first sample is the first :math:`t_k \ge t_0 + \tau`.
- *Attitude estimate*: a complementary filter run on the simulated gyroscope and accelerometer samples (below),
  logged every ``imu_rate / attitude_rate`` filter steps.
- *Commands and motors*: digital signals, copied from the truth at :math:`t_k` (no noise).

**Errors of the inertial sensors**, per axis: :math:`y_k = Q(\bar x_k + b + \sigma \varepsilon_k)` with
:math:`\bar x_k` the boxcar mean above, :math:`b` a constant turn-on bias drawn per record uniformly in
:math:`[-b_{max}, b_{max}]` (``gyro_bias`` / ``accel_bias``), :math:`\varepsilon_k` iid standard normal and

.. math::

    \sigma = N_D \sqrt{f / 2}

the white noise of the noise density :math:`N_D` (``gyro_noise_density``, ``accel_noise_density``) over the
band up to the Nyquist frequency :math:`f/2` of the output rate. :math:`Q` rounds to the resolution of a 16-bit
output at the full-scale range :math:`R` (least significant bit :math:`R / 2^{15}`) and saturates at the range.
No bias instability or random walk is modelled: the chosen part's datasheet does not specify one.

**Barometric altitude**: :math:`h_k = -\bar z_k + \sigma_b \varepsilon_k`, with :math:`\sigma_b` the part's RMS
resolution converted to altitude at sea level, :math:`\Delta h = \Delta p / (\rho g)` (1.225 kg/m^3,
9.80665 m/s^2). The altitude is relative to the record's reference (the autopilot zeroes it at boot); pressure
drift with temperature and weather and the dynamic pressure of the rotor wash are not modelled.

**GPS**: velocity :math:`\mathbf v^{NED} = R(\phi, \theta, \psi) (u, v, w)` plus white noise of standard
deviation ``gps_velocity_std`` (north, east) and ``gps_vertical_factor`` times it (down); position
:math:`(x, y, z)` plus an error that is a first-order Gauss-Markov process per axis,
:math:`e_k = a e_{k-1} + \sqrt{1 - a^2}\, s\, \varepsilon_k`, :math:`a = e^{-T/\tau_p}`, started in its stationary
distribution :math:`N(0, s^2)`, with :math:`s` = ``gps_position_std`` (north, east) and ``gps_vertical_factor``
times it (down), :math:`\tau_p` = ``gps_position_time_constant``: GNSS position errors wander slowly, they do not
jump from one fix to the next.

**Attitude estimate**: the complementary filter of PX4's ``attitude_estimator_q`` (Mahony, Hamel & Pflimlin
2008, explicit complementary filter with gyro-bias estimation), step :math:`\Delta t = 1/` ``imu_rate``, quaternion
:math:`\hat q` (body to NED), :math:`\hat{\mathbf k} = \hat R^T (0, 0, 1)` the estimated down direction in body
axes, :math:`\boldsymbol\omega_y` and :math:`\mathbf a_y` the simulated gyroscope and accelerometer samples:

.. math::

    \mathbf c &= -w_m\, \mathrm{wrap}(\hat\psi - \psi_m)\, \hat{\mathbf k}
                 + w_a\, \hat{\mathbf k} \times \mathbf a_y / |\mathbf a_y|, \\
    \hat{\mathbf b} &\leftarrow \mathrm{clip}(\hat{\mathbf b} + w_b\, \mathbf c\, \Delta t, \pm b_{max})
        \quad (\text{only while } |\boldsymbol\omega_y| < 0.175 \text{ rad/s}), \\
    \hat q &\leftarrow \mathrm{normalise}\big(\hat q + \tfrac12 \hat q \otimes (0, \boldsymbol\omega_y + \hat{\mathbf b}
        + \mathbf c)\, \Delta t\big),

with :math:`w_a, w_m, w_b, b_{max}` = ``attitude_accel_weight``, ``attitude_mag_weight``, ``attitude_bias_weight``,
``attitude_bias_max`` (PX4's ``ATT_W_ACC``, ``ATT_W_MAG``, ``ATT_W_GYRO_BIAS``, ``ATT_BIAS_MAX``) and
:math:`\psi_m` a magnetometer heading, the true heading plus white noise of ``heading_noise`` (the magnetometer
is modelled by the heading it gives, not as a field vector; PX4's GPS acceleration compensation ``ATT_ACC_COMP``
is not modelled). The record starts in flight, so the filter starts as it is after the ground time before
take-off: at the true attitude of the first sample, with the gyro bias learned (:math:`\hat{\mathbf b} = -b`,
clipped). Roll, pitch and yaw are the Z-Y-X Euler angles of :math:`\hat q`; yaw is unwrapped as the simulator's.

References
----------
.. [1] TDK InvenSense, "ICM-42688-P datasheet", DS-000347 (gyroscope and accelerometer).
.. [2] TE Connectivity (MEAS), "MS5611-01BA03 barometric pressure sensor", datasheet DA5611-01BA03.
.. [3] u-blox, "NEO-M8 series data sheet", UBX-15031086 (NEO-M8N GNSS receiver).
.. [4] Honeywell, "3-axis digital compass IC HMC5883L" datasheet (1 to 2 degree heading accuracy).
.. [5] R. Mahony, T. Hamel, J.-M. Pflimlin, "Nonlinear complementary filters on the special orthogonal group",
       IEEE Trans. Automatic Control 53(5), 2008.
.. [6] PX4 Autopilot, ``src/modules/attitude_estimator_q`` (parameters ``ATT_W_ACC`` 0.2, ``ATT_W_MAG`` 0.1,
       ``ATT_W_GYRO_BIAS`` 0.1) and EKF2's ``EKF2_GPS_DELAY`` (110 ms).
"""

from __future__ import annotations

import math
import numbers
import os
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tsfdi._validation import MAX_VALUES, check_rng

__all__ = ["SensorSuite", "sensor_log", "write_sensor_log", "SENSOR_TOPICS", "SIMULATION_RATE"]

#: Rate (Hz) of the true trajectory that :func:`sensor_log` samples: ``simulate_hexacopter(..., fs=1000)``.
SIMULATION_RATE = 1000.0
_G = 9.80665                   # standard gravity, m/s^2 (the g of the accelerometer's datasheet units)
_RHO_G = 1.225 * _G            # sea-level air density times g: Pa per metre of altitude
_DEG = math.pi / 180.0

#: Topics of :func:`sensor_log`: name -> {column: unit}.
SENSOR_TOPICS = {
    "gyro": {"p": "rad/s", "q": "rad/s", "r": "rad/s"},
    "accel": {"ax": "m/s^2", "ay": "m/s^2", "az": "m/s^2"},
    "baro": {"altitude": "m"},
    "gps": {"vn": "m/s", "ve": "m/s", "vd": "m/s", "north": "m", "east": "m", "down": "m"},
    "attitude": {"roll": "rad", "pitch": "rad", "yaw": "rad"},
    "commands": {"roll_command": "rad", "pitch_command": "rad", "yaw_command": "rad", "collective": "rad/s",
                 "roll_control": "rad/s", "pitch_control": "rad/s", "yaw_control": "rad/s"},
    "motors": {f"motor_command{i}": "rad/s" for i in range(1, 7)},
}
#: True-state channels of the record that :func:`sensor_log` reads.
_NEEDED = ("x", "y", "z", "roll", "pitch", "yaw", "u", "v", "w", "p", "q", "r", "ax", "ay", "az",
           *SENSOR_TOPICS["commands"], *SENSOR_TOPICS["motors"])


@dataclass(frozen=True)
class SensorSuite:
    r"""The sensors of :func:`sensor_log`: rates, noise, biases, ranges and the attitude filter's gains (SI units).

    Rates are in Hz and must divide the 1 kHz of the simulation (``attitude_rate`` must divide ``imu_rate``).
    Defaults: the parts of a current Pixhawk-class autopilot.

    Attributes
    ----------
    imu_rate : float
        500 Hz: output rate of the gyroscope and accelerometer (the part runs up to 32 kHz, DS-000347; PX4 logs
        its IMU at 200-1000 Hz). Anti-aliasing: the boxcar mean of the 1 kHz truth over each period.
    gyro_noise_density : float
        2.8 mdps/sqrt(Hz) = 4.89e-5 rad/s/sqrt(Hz): gyroscope rate noise spectral density of the TDK InvenSense
        ICM-42688-P (datasheet DS-000347, features list).
    gyro_bias : float
        0.5 dps = 8.73e-3 rad/s: largest turn-on bias per axis, the ICM-42688-P's initial zero-rate-output
        tolerance (DS-000347, gyroscope specifications; uncalibrated). 0 for a calibrated gyroscope.
    gyro_range : float
        2000 dps = 34.9 rad/s: full-scale range (the ICM-42688-P's largest, DS-000347, the range PX4 configures);
        resolution ``gyro_range / 2**15`` (16-bit output, 1/16.4 dps).
    accel_noise_density : float
        70 micro-g/sqrt(Hz) = 6.86e-4 m/s^2/sqrt(Hz): accelerometer noise spectral density of the ICM-42688-P
        (DS-000347, features list).
    accel_bias : float
        20 mg = 0.196 m/s^2: largest turn-on bias per axis, the ICM-42688-P's initial zero-g tolerance
        (DS-000347, accelerometer specifications; uncalibrated). 0 for a calibrated accelerometer.
    accel_range : float
        16 g = 156.9 m/s^2: full-scale range (the ICM-42688-P's largest, DS-000347); resolution
        ``accel_range / 2**15`` (2048 LSB/g).
    baro_rate : float
        50 Hz: barometric altitude rate. The MS5611 converts in 8.22 ms at oversampling 4096 (datasheet
        DA5611-01BA03) and alternates pressure and temperature conversions: about 50 pressure samples per second.
    baro_noise : float
        0.10 m: RMS altitude noise, the MS5611's resolution 0.012 mbar (1.2 Pa) at oversampling 4096 (DA5611-01BA03,
        "high resolution module, 10 cm") divided by rho g at sea level.
    gps_rate : float
        10 Hz: navigation update rate of a u-blox NEO-M8N (up to 10 Hz with concurrent GNSS, UBX-15031086).
    gps_latency : float
        0.11 s: age of a GPS solution when it is logged, PX4 EKF2's default ``EKF2_GPS_DELAY`` (110 ms); a whole
        number of milliseconds.
    gps_velocity_std : float
        0.074 m/s: standard deviation of the north and east velocity errors. The NEO-M8N's velocity accuracy is
        0.05 m/s at 50 % (UBX-15031086); for a normal error the 50 % level of :math:`|e|` is 0.6745 sigma.
    gps_position_std : float
        2.12 m: standard deviation of the north and east position errors, from the NEO-M8N's 2.5 m CEP
        (autonomous fix, UBX-15031086): CEP = 1.1774 sigma for a circular normal error.
    gps_vertical_factor : float
        1.5: the down errors (velocity and position) are this many times the horizontal ones. A typical-part
        choice: the data sheet gives no vertical accuracy; GNSS vertical dilution is typically 1.5-2 times the
        horizontal one.
    gps_position_time_constant : float
        60 s: correlation time of the position error (Gauss-Markov). A typical-part choice: GNSS position errors
        follow satellite geometry and the atmosphere over tens of seconds to minutes; the data sheet gives none.
    attitude_rate : float
        250 Hz: logging rate of the attitude estimate (the filter runs at ``imu_rate``).
    attitude_accel_weight, attitude_mag_weight, attitude_bias_weight : float
        0.2, 0.1, 0.1 (1/s): PX4 ``attitude_estimator_q``'s defaults ``ATT_W_ACC``, ``ATT_W_MAG``,
        ``ATT_W_GYRO_BIAS``.
    attitude_bias_max : float
        0.05 rad/s: PX4's ``ATT_BIAS_MAX``, the largest gyro bias the filter estimates.
    heading_noise : float
        1 deg = 0.0175 rad: standard deviation of the magnetometer heading, the lower end of the Honeywell
        HMC5883L's "1 to 2 degree compass heading accuracy" (datasheet), taken as white noise per filter step (a
        typical-part choice).
    control_rate : float
        250 Hz: logging rate of the controller's commands and the motor outputs (copied from the truth).

    Raises
    ------
    TypeError
        A field that is not a real number.
    ValueError
        A negative or non-finite value, a zero rate, range or time constant, a rate that does not divide 1000 Hz
        (``attitude_rate``: ``imu_rate``), a latency that is not a whole number of milliseconds.
    """

    imu_rate: float = 500.0
    gyro_noise_density: float = 2.8e-3 * _DEG
    gyro_bias: float = 0.5 * _DEG
    gyro_range: float = 2000.0 * _DEG
    accel_noise_density: float = 70e-6 * _G
    accel_bias: float = 0.020 * _G
    accel_range: float = 16.0 * _G
    baro_rate: float = 50.0
    baro_noise: float = 1.2 / _RHO_G
    gps_rate: float = 10.0
    gps_latency: float = 0.11
    gps_velocity_std: float = 0.05 / 0.6745
    gps_position_std: float = 2.5 / 1.1774
    gps_vertical_factor: float = 1.5
    gps_position_time_constant: float = 60.0
    attitude_rate: float = 250.0
    attitude_accel_weight: float = 0.2
    attitude_mag_weight: float = 0.1
    attitude_bias_weight: float = 0.1
    attitude_bias_max: float = 0.05
    heading_noise: float = 1.0 * _DEG
    control_rate: float = 250.0

    def __post_init__(self) -> None:
        positive = {"gyro_range", "accel_range", "gps_position_time_constant", "gps_vertical_factor"}
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
                raise TypeError(f"{f.name} must be a real number, got {v!r} ({type(v).__name__})")
            if not math.isfinite(v) or v < 0 or (v == 0 and (f.name in positive or f.name.endswith("_rate"))):
                kind = "positive" if f.name in positive or f.name.endswith("_rate") else "non-negative"
                raise ValueError(f"{f.name} must be a finite {kind} number, got {v!r}")
        for name in ("imu_rate", "baro_rate", "gps_rate", "control_rate"):
            _steps(getattr(self, name), name, SIMULATION_RATE, "the 1000 Hz of the simulation")
        _steps(self.attitude_rate, "attitude_rate", self.imu_rate, f"imu_rate = {self.imu_rate:g} Hz")
        ms = self.gps_latency * SIMULATION_RATE
        if abs(ms - round(ms)) > 1e-6:
            raise ValueError(f"gps_latency must be a whole number of milliseconds (simulation steps), got "
                             f"{self.gps_latency!r} s")


def _steps(rate: float, name: str, base: float, what: str) -> int:
    """``base / rate`` as an int, or raise naming ``name``."""
    n = base / rate
    if n < 1 - 1e-9 or abs(n - round(n)) > 1e-9:
        raise ValueError(f"{name} must divide {what} into whole periods (1000, 500, 250, 200, 100, 50, ... Hz), "
                         f"got {rate!r} Hz")
    return int(round(n))


# ------------------------------------------------------------------------------------------------- the record
def _truth(record: Any) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The record's time stamps (s) and its needed channels as float arrays over time, validated."""
    import xarray as xr

    if not isinstance(record, xr.Dataset):
        raise TypeError(f"record must be one record of simulate_hexacopter(..., fs=1000), an xarray.Dataset, got "
                        f"{type(record).__name__}")
    if "record" in record.dims:
        if record.sizes["record"] != 1:
            raise ValueError(f"record must be one record: it has {record.sizes['record']} along 'record'; pick one "
                             "with data.isel(record=i)")
        record = record.isel(record=0)
    if "time" not in record.coords:
        raise ValueError("record has no 'time' coordinate (seconds)")
    t = record["time"].values
    if np.issubdtype(t.dtype, np.timedelta64):
        t = t / np.timedelta64(1, "s")
    if not np.issubdtype(t.dtype, np.number) or t.ndim != 1:
        raise ValueError(f"record's time coordinate must hold seconds, got dtype {t.dtype}")
    t = t.astype(np.float64)
    if t.size < 2:
        raise ValueError(f"record must hold at least 2 time samples, got {t.size}")
    steps = np.diff(t)
    if not np.all(np.abs(steps - 1.0 / SIMULATION_RATE) <= 1e-6 / SIMULATION_RATE):
        med = float(np.median(steps))
        rate = f"{1.0 / med:g} Hz" if med > 0 else "not uniformly"
        raise ValueError(f"record is sampled at {rate}, not uniformly at 1000 Hz: sensor_log samples the 1 kHz "
                         "truth; simulate it with simulate_hexacopter(..., fs=1000)")
    if t.size * (len(_NEEDED) + 16) > MAX_VALUES:
        raise ValueError(f"record is too long ({t.size} samples): split it")
    missing = [c for c in _NEEDED if c not in record.data_vars]
    if missing:
        raise ValueError(f"record has no channel {', '.join(map(repr, missing))}: sensor_log needs the true "
                         f"states {list(_NEEDED)} (simulate_hexacopter(..., fs=1000))")
    out = {}
    for c in _NEEDED:
        da = record[c]
        if da.dims != ("time",):
            raise ValueError(f"record's channel {c!r} must be over 'time' only, got dims {da.dims}")
        v = np.asarray(da.values, dtype=np.float64)
        bad = ~np.isfinite(v)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"record's channel {c!r} is NaN or infinite from t = {t[i]:g} s (a lost aircraft, "
                             "lost_control): cut the record before it")
        out[c] = v
    return t, out


def _rotation(roll: np.ndarray, pitch: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """Body-to-NED rotation matrices (Z-Y-X Euler angles), shape (n, 3, 3)."""
    cf, sf, ct, st, cp, sp = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    return np.stack([np.stack([ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp], -1),
                     np.stack([ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp], -1),
                     np.stack([-st, sf * ct, cf * ct], -1)], -2)


def _boxcar(x: np.ndarray, n: int, count: int) -> np.ndarray:
    """Means of ``x`` (time first) over the ``count`` periods of ``n`` samples that end at samples n, 2n, ..."""
    return x[1:count * n + 1].reshape(count, n, *x.shape[1:]).mean(axis=1)


def _inertial(mean: np.ndarray, density: float, bias_max: float, full_scale: float, rate: float,
              gen: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A 3-axis inertial sensor's samples from the boxcar means of the truth, and its turn-on bias."""
    bias = gen.uniform(-bias_max, bias_max, 3)
    y = mean + bias + density * math.sqrt(rate / 2.0) * gen.standard_normal(mean.shape)
    lsb = full_scale / 2.0**15
    return np.clip(np.round(y / lsb), -2.0**15, 2.0**15 - 1) * lsb, bias


def _attitude(gyro: np.ndarray, accel: np.ndarray, heading: np.ndarray, start: tuple[float, float, float],
              bias0: np.ndarray, dt: float, suite: SensorSuite) -> np.ndarray:
    """Roll, pitch, wrapped yaw of PX4's attitude_estimator_q run on the samples (see the module's Notes)."""
    roll, pitch, yaw = start
    cr, sr, cp, sp, cy, sy = (math.cos(roll / 2), math.sin(roll / 2), math.cos(pitch / 2), math.sin(pitch / 2),
                              math.cos(yaw / 2), math.sin(yaw / 2))
    q0, q1, q2, q3 = (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
                      cr * cp * sy - sr * sp * cy)
    bmax = suite.attitude_bias_max
    bx, by, bz = (min(max(-float(b), -bmax), bmax) for b in bias0)
    wa, wm, wb = suite.attitude_accel_weight, suite.attitude_mag_weight, suite.attitude_bias_weight
    out = np.empty((len(gyro), 3))
    g_list, a_list, h_list = gyro.tolist(), accel.tolist(), heading.tolist()
    for i in range(len(g_list)):
        gx, gy, gz = g_list[i]
        ax, ay, az = a_list[i]
        kx, ky, kz = 2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3
        psi = math.atan2(2 * (q0 * q3 + q1 * q2), 1 - 2 * (q2 * q2 + q3 * q3))
        err = math.remainder(psi - h_list[i], 2 * math.pi) * wm
        cx, cy_, cz = -err * kx, -err * ky, -err * kz
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        if norm > 0:
            ax, ay, az = ax / norm, ay / norm, az / norm
            cx += wa * (ky * az - kz * ay)
            cy_ += wa * (kz * ax - kx * az)
            cz += wa * (kx * ay - ky * ax)
        if math.sqrt(gx * gx + gy * gy + gz * gz) < 0.175:
            bx = min(max(bx + cx * wb * dt, -bmax), bmax)
            by = min(max(by + cy_ * wb * dt, -bmax), bmax)
            bz = min(max(bz + cz * wb * dt, -bmax), bmax)
        wx, wy, wz = gx + bx + cx, gy + by + cy_, gz + bz + cz
        h = 0.5 * dt
        q0, q1, q2, q3 = (q0 + h * (-q1 * wx - q2 * wy - q3 * wz), q1 + h * (q0 * wx + q2 * wz - q3 * wy),
                          q2 + h * (q0 * wy - q1 * wz + q3 * wx), q3 + h * (q0 * wz + q1 * wy - q2 * wx))
        n = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
        q0, q1, q2, q3 = q0 / n, q1 / n, q2 / n, q3 / n
        out[i, 0] = math.atan2(2 * (q0 * q1 + q2 * q3), 1 - 2 * (q1 * q1 + q2 * q2))
        out[i, 1] = math.asin(min(max(2 * (q0 * q2 - q3 * q1), -1.0), 1.0))
        out[i, 2] = math.atan2(2 * (q0 * q3 + q1 * q2), 1 - 2 * (q2 * q2 + q3 * q3))
    return out


def _frame(time: np.ndarray, values: np.ndarray, topic: str) -> pd.DataFrame:
    units = SENSOR_TOPICS[topic]
    frame = pd.DataFrame(values, index=pd.Index(time, name="time", dtype=np.float64), columns=list(units))
    frame.attrs["units"] = dict(units)
    return frame


def sensor_log(record: Any, suite: SensorSuite | None = None, *, rng: Any = None) -> dict[str, pd.DataFrame]:
    r"""The topics an autopilot logs, simulated from one record of the hexacopter's true 1 kHz trajectory.

    Parameters
    ----------
    record : xarray.Dataset
        One record of ``simulate_hexacopter(..., fs=1000)``: variables over ``time`` (seconds, 1 kHz), or over
        ``record`` (of length 1) and ``time``. It must hold the true states ``x, y, z`` (NED position, m),
        ``roll, pitch, yaw`` (rad), ``u, v, w`` (body velocity, m/s), ``p, q, r`` (body rates, rad/s), ``ax, ay,
        az`` (specific force in body axes, m/s^2: what an accelerometer at the centre of gravity measures), the
        controller's signals (``roll_command``, ``pitch_command``, ``yaw_command``, ``collective``,
        ``roll_control``, ``pitch_control``, ``yaw_control``) and ``motor_command1`` ... ``motor_command6``
        (rad/s), all finite.
    suite : SensorSuite, optional
        The sensors (default: ``SensorSuite()``, the cited parts).
    rng : None, int or numpy.random.Generator
        Randomness of the biases and noise (the same seed gives the same log).

    Returns
    -------
    dict of str to pandas.DataFrame
        One DataFrame per topic, indexed by the time in seconds (a float index named ``"time"``, on multiples of
        the topic's period from the record's first sample; see the module's Notes), units in ``frame.attrs["units"]``:

        - ``"gyro"`` (``imu_rate``): ``p, q, r`` body rates, rad/s;
        - ``"accel"`` (``imu_rate``): ``ax, ay, az`` specific force in body axes, m/s^2 (about ``(0, 0, -g)``
          level at rest: NED, z down);
        - ``"baro"`` (``baro_rate``): ``altitude`` above the record's reference, m (``-z`` plus noise);
        - ``"gps"`` (``gps_rate``, ``gps_latency`` behind): ``vn, ve, vd`` NED velocity, m/s; ``north, east,
          down`` NED position, m;
        - ``"attitude"`` (``attitude_rate``): ``roll, pitch, yaw`` of the complementary filter, rad (yaw
          unwrapped);
        - ``"commands"`` (``control_rate``): ``roll_command, pitch_command, yaw_command`` (rad), ``collective,
          roll_control, pitch_control, yaw_control`` (rad/s), copied;
        - ``"motors"`` (``control_rate``): ``motor_command1`` ... ``motor_command6`` rotor speed commands, rad/s,
          copied.

    Raises
    ------
    TypeError
        ``record`` not an xarray.Dataset; ``suite`` not a :class:`SensorSuite`; a bad ``rng``.
    ValueError
        ``record`` not sampled at 1 kHz, with more than one record, without a needed channel (named), with a
        NaN / inf (a lost aircraft), or shorter than one period of the slowest topic.

    Notes
    -----
    The models and the cited parameters are in :class:`SensorSuite` and the module's Notes.

    Examples
    --------
    >>> from tsfdi.datasets import simulate_hexacopter
    >>> record = simulate_hexacopter(duration=2.0, fs=1000, turbulence="light").isel(record=0)
    >>> log = sensor_log(record, rng=0)
    >>> list(log)
    ['gyro', 'accel', 'baro', 'gps', 'attitude', 'commands', 'motors']
    >>> len(log["gyro"]), len(log["baro"]), len(log["gps"])    # 500, 50, 10 Hz over 1.999 s; GPS from 0.2 s
    (999, 99, 18)
    """
    suite = SensorSuite() if suite is None else suite
    if not isinstance(suite, SensorSuite):
        raise TypeError(f"suite must be a SensorSuite, got {type(suite).__name__}")
    gen = check_rng(rng)
    t, x = _truth(record)
    last = t.size - 1                                          # samples after the first one
    n_imu, n_baro, n_gps, n_ctl = (int(round(SIMULATION_RATE / f)) for f in (suite.imu_rate, suite.baro_rate,
                                                                             suite.gps_rate, suite.control_rate))
    lag = int(round(suite.gps_latency * SIMULATION_RATE))
    gps_first = max(1, -(-lag // n_gps))                       # first k with k n >= lag
    need = max(n_imu, n_baro, n_ctl, gps_first * n_gps, n_imu * int(round(suite.imu_rate / suite.attitude_rate)))
    if last < need:
        raise ValueError(f"record is too short: {last / SIMULATION_RATE:g} s after its first sample; the suite's "
                         f"slowest topic needs {need / SIMULATION_RATE:g} s")

    log = {}
    # gyroscope and accelerometer
    k_imu = last // n_imu
    t_imu = t[n_imu:k_imu * n_imu + 1:n_imu]
    rates = np.column_stack([x["p"], x["q"], x["r"]])
    force = np.column_stack([x["ax"], x["ay"], x["az"]])
    gyro, gyro_bias = _inertial(_boxcar(rates, n_imu, k_imu), suite.gyro_noise_density, suite.gyro_bias,
                                suite.gyro_range, suite.imu_rate, gen)
    accel, _ = _inertial(_boxcar(force, n_imu, k_imu), suite.accel_noise_density, suite.accel_bias,
                         suite.accel_range, suite.imu_rate, gen)
    log["gyro"] = _frame(t_imu, gyro, "gyro")
    log["accel"] = _frame(t_imu, accel, "accel")
    # attitude estimate
    idx = np.arange(1, k_imu + 1) * n_imu
    heading = x["yaw"][idx] + suite.heading_noise * gen.standard_normal(k_imu)
    est = _attitude(gyro, accel, heading, (x["roll"][0], x["pitch"][0], x["yaw"][0]), gyro_bias,
                    1.0 / suite.imu_rate, suite)
    yaw = np.unwrap(est[:, 2])
    est[:, 2] = yaw + 2 * np.pi * np.round((x["yaw"][0] - yaw[0]) / (2 * np.pi))
    m = int(round(suite.imu_rate / suite.attitude_rate))
    log["attitude"] = _frame(t_imu[m - 1::m], est[m - 1::m], "attitude")
    # barometric altitude
    k_baro = last // n_baro
    altitude = -_boxcar(x["z"], n_baro, k_baro) + suite.baro_noise * gen.standard_normal(k_baro)
    log["baro"] = _frame(t[n_baro:k_baro * n_baro + 1:n_baro], altitude[:, None], "baro")
    # GPS
    idx = np.arange(gps_first, last // n_gps + 1) * n_gps
    src = idx - lag
    ned = np.einsum("nij,nj->ni", _rotation(x["roll"][src], x["pitch"][src], x["yaw"][src]),
                    np.column_stack([x["u"][src], x["v"][src], x["w"][src]]))
    scale = np.array([1.0, 1.0, suite.gps_vertical_factor])
    vel = ned + suite.gps_velocity_std * scale * gen.standard_normal(ned.shape)
    a = math.exp(-1.0 / (suite.gps_rate * suite.gps_position_time_constant))
    shocks = gen.standard_normal(ned.shape)
    err = np.empty_like(ned)
    err[0] = shocks[0]
    for i in range(1, len(err)):
        err[i] = a * err[i - 1] + math.sqrt(1.0 - a * a) * shocks[i]
    pos = np.column_stack([x["x"][src], x["y"][src], x["z"][src]]) + suite.gps_position_std * scale * err
    log["gps"] = _frame(t[idx], np.hstack([vel, pos]), "gps")
    # controller commands and motor outputs: digital signals, copied
    idx = np.arange(1, last // n_ctl + 1) * n_ctl
    for topic in ("commands", "motors"):
        log[topic] = _frame(t[idx], np.column_stack([x[c][idx] for c in SENSOR_TOPICS[topic]]), topic)
    return {topic: log[topic] for topic in SENSOR_TOPICS}


def write_sensor_log(path: str | os.PathLike, log: dict[str, pd.DataFrame]) -> list[Path]:
    """Write a log of :func:`sensor_log` as a folder of per-topic CSV files, as a flight log's topics.

    Each topic goes to ``<path>/<topic>.csv`` with its time (seconds) in the first column, ``time``, and the
    values at full precision; :func:`tsfdi.read_records` reads the folder (``topics=[...]``, ``fs=...``) and puts
    the topics on one grid as it does a real log's.

    Parameters
    ----------
    path : str or path-like
        The folder (created if missing; files already there are never overwritten).
    log : dict of str to pandas.DataFrame
        Topic name -> DataFrame indexed by the time in seconds (float index named ``"time"``).

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of ``log``.

    Raises
    ------
    TypeError
        ``log`` not a dict of DataFrames.
    ValueError
        An empty ``log``; a topic name that is not a plain file name; a topic without a float time index named
        ``"time"`` or with a column named ``"time"``; a file that already exists.
    """
    if not isinstance(log, dict) or not all(isinstance(v, pd.DataFrame) for v in log.values()):
        raise TypeError(f"log must be a dict of topic name -> pandas.DataFrame (sensor_log's output), got "
                        f"{type(log).__name__}")
    if not log:
        raise ValueError("log holds no topic")
    folder = Path(path)
    files = []
    for topic, frame in log.items():
        if not isinstance(topic, str) or not topic or os.sep in topic or topic.startswith(".") or "/" in topic:
            raise ValueError(f"log: topic name {topic!r} must be a plain file name")
        if frame.index.name != "time" or not pd.api.types.is_float_dtype(frame.index):
            raise ValueError(f"log: topic {topic!r} must be indexed by the time in seconds (a float index named "
                             f"'time'), got {frame.index.name!r} of dtype {frame.index.dtype}")
        if "time" in frame.columns:
            raise ValueError(f"log: topic {topic!r} has a column named 'time', which would clash with its time")
        file = folder / f"{topic}.csv"
        if file.exists():
            raise ValueError(f"path: {file} already exists; write the log to a new folder")
        files.append(file)
    folder.mkdir(parents=True, exist_ok=True)
    for file, frame in zip(files, log.values()):
        frame.to_csv(file, index=True, index_label="time")
    return files
