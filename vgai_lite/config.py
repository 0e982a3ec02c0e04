"""Every constant of the flocking problem, in one place.

Introduced in notebook 01. Each field carries the paper's value (Hu et al., ICASSP 2021, section 3.1
and "Implementation Details") or, where the paper is silent or contradicts its public reference
code, the value we chose, with the reason beside it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

POTENTIALS = ("paper", "reference")

DISTANCE_FLOOR = 1e-3
"""m: the pair distance below which eq. 3's potential and the DAGNN's 1/||r||^2, 1/||r||^4 features
are evaluated as if the pair were this far apart (``controllers.potential``, ``features.local_features``).
The paper is silent; at 0 m they are 1/0 and two coincident agents would make the expert's
acceleration NaN. At 1 mm the potential's push, about 2/||r||^3 = 2e9 m/s^2, is already 10^8 times
the actuators' limit u_max, so the floor changes no saturated command of any reachable state;
it only keeps the arithmetic finite (also in float32). Coincident agents (r_ij = 0 exactly) give each
other no push, as no direction is defined; their other neighbours and velocities still act.
It is not a FlockConfig field: it is numerical safety, not part of the problem, and changing it
would leave every trained controller and cached result unchanged."""
INIT_METHODS = ("reject", "repair")


@dataclass(frozen=True)
class FlockConfig:
    """The flocking problem's constants.

    Attributes:
        N: number of agents (paper: 50).
        R: communication radius in m; i and j are neighbours iff ||r_i - r_j|| <= R (paper: 1.5).
        v_init: initial velocity scale in m/s (paper: 3.0). Each agent's velocity is uniform in
            [-v_init, v_init]^2, plus one flock-wide bias uniform in [-0.3 v_init, 0.3 v_init]^2.
        Ts: sampling period in s (paper: 0.01).
        T: steps per episode (paper: silent; 200 steps = 2 s, by which time the expert has
            flocked: its action is zero after about step 100).
        u_max: per-axis acceleration saturation in m/s^2 (paper: 30).
        rho: radius of the collision potential of eq. 3 in m; its gradient vanishes beyond it
            (paper: "the minimum distance allowed"; no value given. 0.5 m, calibrated so that the
            Local heuristic's relative cost matches the paper's 4.13 within about 5 %).
        potential: "paper" for U = 1/||r||^2 - log||r||^2 as eq. 3 prints it (purely repulsive),
            "reference" for the public reference code's U = 1/||r||^2 + log||r||^2 (repulsive
            below 1 m, attractive between 1 m and rho when rho > 1).
        init_radius_exponent: initial positions are uniform on a disc of radius N**exponent.
            The paper's text says sqrt(N) (exponent 0.5); its reference code draws
            sqrt(U(0, sqrt(N))), a disc of radius N**0.25. With R = 1.5 the sqrt(N) disc never gives
            every agent two neighbours (0 in 200,000 draws), so we follow the code: 0.25.
        bias_fraction: the flock-wide velocity bias is uniform in [-b v_init, b v_init]^2 with
            b = 0.3 (paper: 3/10).
        min_neighbours: resample unless every agent has at least this many neighbours (paper: 2).
        min_init_distance: resample if any pair starts closer than this, in m (paper: 0.2).
        init_method: how a draw that violates the constraints is redrawn. "reject" (the paper's
            words, and exact): redraw the whole swarm. "repair": redraw only the agents that start
            closer than min_init_distance to an earlier agent, repeatedly, then reject the swarm only
            if an agent lacks neighbours. Whole-swarm rejection accepts 1 draw in 1,200 at N = 50 but
            about 1 in 400,000 at N = 75 and 1 in 10^9 at N = 100, so larger teams need "repair".
        max_init_tries: give up (with an error) once more than this many candidate draws have been
            made per accepted initial state; about 1 draw in 1,200 is accepted at the defaults.
    """

    N: int = 50
    R: float = 1.5
    v_init: float = 3.0
    Ts: float = 0.01
    T: int = 200
    u_max: float = 30.0
    rho: float = 0.5
    potential: str = "paper"
    init_radius_exponent: float = 0.25
    bias_fraction: float = 0.3
    min_neighbours: int = 2
    min_init_distance: float = 0.2
    init_method: str = "reject"
    max_init_tries: int = 100_000

    def __post_init__(self) -> None:
        def need(ok: bool, what: str) -> None:
            if not ok:
                raise ValueError(f"FlockConfig: {what}")

        need(isinstance(self.N, int) and self.N >= 2,
             f"N must be an integer >= 2 (a swarm needs two agents), got {self.N!r}")
        for name in ("R", "Ts", "u_max", "rho", "v_init"):
            value = getattr(self, name)
            need(isinstance(value, (int, float)) and math.isfinite(value) and value > 0,
                 f"{name} must be a finite number > 0, got {value!r}")
        need(isinstance(self.T, int) and self.T >= 1, f"T must be an integer >= 1, got {self.T!r}")
        need(self.potential in POTENTIALS,
             f"potential must be one of {POTENTIALS}, got {self.potential!r}")
        need(self.init_radius_exponent > 0,
             f"init_radius_exponent must be > 0, got {self.init_radius_exponent!r}")
        need(0 <= self.bias_fraction, f"bias_fraction must be >= 0, got {self.bias_fraction!r}")
        need(isinstance(self.min_neighbours, int) and 0 <= self.min_neighbours < self.N,
             f"min_neighbours must be an integer in [0, N-1] = [0, {self.N - 1}], "
             f"got {self.min_neighbours!r}")
        need(0 <= self.min_init_distance < self.R,
             f"min_init_distance must be in [0, R) = [0, {self.R}), got {self.min_init_distance!r}")
        need(self.init_method in INIT_METHODS,
             f"init_method must be one of {INIT_METHODS}, got {self.init_method!r}")
        need(isinstance(self.max_init_tries, int) and self.max_init_tries > 0,
             f"max_init_tries must be a positive integer, got {self.max_init_tries!r}")

    @property
    def init_radius(self) -> float:
        """Radius in m of the disc the initial positions are drawn from: N**init_radius_exponent."""
        return float(self.N) ** self.init_radius_exponent

    def replace(self, **changes) -> "FlockConfig":
        """A copy with some fields changed (validated again), e.g. ``cfg.replace(R=2.0)``."""
        return replace(self, **changes)

    def to_dict(self) -> dict:
        return config_dict(self)


def config_dict(config) -> dict:
    """A config dataclass as plain JSON-ready values (nested configs as dicts, tuples as lists): the
    form stored in checkpoints and hashed into cache keys. Every config's ``to_dict`` is this."""
    def plain(x):
        if isinstance(x, dict):
            return {k: plain(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [plain(v) for v in x]
        return x

    return plain(asdict(config))
