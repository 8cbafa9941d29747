"""A speed observer for one wheel: the nominal wheel driven by the applied voltage, corrected
by the encoder's position.

The measured speed of a 728-count encoder moves in quanta of one count per 20 ms window
(25.9 mm/s); a proportional term on it turns every toggle of the count into a voltage step,
which on a slippery floor carries the tyre over its friction limit (docs/control.md, slip
chatter). The observer estimates the speed between counts from the wheel's model and the
count's position, whose quantum is only 0.52 mm.

Model (the default form's nominal wheel, DC gain ``1 / g`` and time constant ``tau``), with
an input disturbance ``d`` in speed units (a load, another motor constant, friction: whatever
makes the wheel need another voltage than ``g`` times its speed), held over one period ``h``
with ``w = V / g`` (zero-order hold, exact; ``a = exp(-h / tau)``)::

    u_k+1 = a u_k + (1 - a) (w_k + d_k)                 rim speed [m/s]
    x_k+1 = x_k + tau (1 - a) u_k + (h - tau (1 - a)) (w_k + d_k)      rim position [m]
    d_k+1 = d_k

The measurement is the position ``y_k`` the encoder speeds add up to (``sum v_meas h``: the
count times its distance, exact). A current estimator (predict with the voltage held over
the last period, then correct with ``y_k``; Franklin, Powell and Workman, Digital Control of
Dynamic Systems, Sec. 8.2.2) with its three error poles at ``exp(-bandwidth h)``: the gains
are Ackermann's for that pole, ``L = phi(A) [C A; C A^2; C A^3]^-1 e_3``,
``phi(z) = (z - p)^3``. The disturbance state makes the speed estimate unbiased on a wheel
whose constants differ from the model's in steady state; the transient is the model's.

Pure Python floats: the law calls it every step.
"""

import math

__all__ = ["SpeedObserver"]


def _matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def _solve(matrix, rhs):
    """``matrix^-1 rhs`` for a 3 x 3 matrix (Cramer's rule)."""
    def det(m):
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    whole = det(matrix)
    out = []
    for column in range(3):
        replaced = [[rhs[i] if j == column else matrix[i][j] for j in range(3)]
                    for i in range(3)]
        out.append(det(replaced) / whole)
    return out


class SpeedObserver:
    """The rim speed between encoder counts (see the module docstring).

    Parameters
    ----------
    volts_per_speed : float
        ``g`` [V s/m], the model's steady voltage per rim speed.
    time_constant : float
        ``tau`` [s], the model's mechanical time constant, > 0.
    bandwidth : float
        The error poles' rate [rad/s], > 0: ``p = exp(-bandwidth h)``.

    Attributes
    ----------
    position, speed, disturbance : float
        The estimate after the last update [m, m/s, m/s].
    measured_position : float
        ``sum v_meas h`` so far [m].
    """

    def __init__(self, volts_per_speed, time_constant, bandwidth):
        self.g = float(volts_per_speed)
        self.tau = float(time_constant)
        self.bandwidth = float(bandwidth)
        self._step = None
        self._matrices = None
        self.reset()

    def reset(self):
        """At rest at position 0, no disturbance."""
        self.position = self.speed = self.disturbance = 0.0
        self.measured_position = 0.0

    def matrices(self, h):
        """``(A, B, L)`` for the step ``h``: transition (3 x 3), input column, gains."""
        if h != self._step:
            a = math.exp(-h / self.tau)
            lag = self.tau * (1.0 - a)
            transition = [[1.0, lag, h - lag], [0.0, a, 1.0 - a], [0.0, 0.0, 1.0]]
            drive = [h - lag, 1.0 - a, 0.0]
            pole = math.exp(-self.bandwidth * h)
            shifted = [[transition[i][j] - (pole if i == j else 0.0) for j in range(3)]
                       for i in range(3)]
            phi = _matmul(_matmul(shifted, shifted), shifted)
            power = transition
            rows = []
            for _ in range(3):
                rows.append(list(power[0]))          # C A^k with C = [1, 0, 0]
                power = _matmul(power, transition)
            column = _solve(rows, [0.0, 0.0, 1.0])
            gains = [sum(phi[i][k] * column[k] for k in range(3)) for i in range(3)]
            self._step = h
            self._matrices = (transition, drive, gains)
        return self._matrices

    def update(self, v_meas, h, voltage):
        """Advance over the period that just ended and correct with its measurement.

        Parameters
        ----------
        v_meas : float
            The encoder's speed over the period [m/s].
        h : float
            The period [s], > 0.
        voltage : float
            The voltage held over that period [V] (the controller's last output).

        Returns
        -------
        float
            The rim speed estimate at the period's end [m/s].
        """
        transition, drive, gains = self.matrices(h)
        state = (self.position, self.speed, self.disturbance)
        w = voltage / self.g
        predicted = [sum(transition[i][k] * state[k] for k in range(3)) + drive[i] * w
                     for i in range(3)]
        self.measured_position += v_meas * h
        innovation = self.measured_position - predicted[0]
        self.position, self.speed, self.disturbance = (
            predicted[i] + gains[i] * innovation for i in range(3))
        return self.speed
