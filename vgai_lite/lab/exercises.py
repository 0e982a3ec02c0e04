"""Automatic checks for the book's exercises.

Introduced in notebook 01. Each check takes the student's function, runs it on fresh random inputs
against the library's own implementation, prints "passed" or what was expected on which input
(never the solution's code), and returns a CheckResult. A check never raises: a crashing or wrong
answer gives a message, not a broken notebook.
"""

from __future__ import annotations

import json
import math
import os
import traceback
from dataclasses import dataclass
from typing import Callable

import torch

from ..aggregation import AggregationBuffer, aggregation_sequence
from ..config import FlockConfig
from ..controllers import potential_gradient
from ..features import local_features
from ..flocking import flocking_cost, velocity_variance
from ..graphs import adjacency, gso
from ..render import RenderConfig, bearing_to_column
from .library_guard import LIBRARY_CALL, guarded


@dataclass
class CheckResult:
    """The outcome of one exercise check; truthy when passed."""

    exercise: str
    passed: bool
    message: str

    def __bool__(self) -> bool:
        return self.passed

    def __str__(self) -> str:
        mark = "PASSED" if self.passed else "NOT PASSED"
        return f"[{mark}] exercise {self.exercise} ({EXERCISES.get(self.exercise, '?')}): {self.message}"


class AnswerMismatch(Exception):
    """Raised by a check's own tests (a shape, a type): the answer is not what was expected. Reported
    as what was expected, not as an error of the student's function."""


def _fresh_generator() -> torch.Generator:
    return torch.Generator().manual_seed(int.from_bytes(os.urandom(6), "little"))


def _close(got: torch.Tensor, want: torch.Tensor) -> bool:
    """Equal up to float32 rounding: an answer computed in float32, or in another order, passes."""
    return torch.allclose(got.to(want.dtype), want, rtol=1e-4, atol=1e-6)


def _fmt(x: torch.Tensor) -> str:
    return "[" + ", ".join(f"{float(a):.4g}" for a in x.flatten()) + "]"


EXERCISES: dict[str, str] = {
    "01.1": "potential gradient (eq. 3)",
    "01.2": "flocking cost (eq. 1)",
    "02.1": "delayed aggregation sequence (eq. 6)",
    "02.2": "symmetric normalised GSO",
    "03.1": "local features (DAGNN input)",
    "03.2": "one DAgger round's data aggregation",
    "03.3": "DAgger's training loop",
    "04.1": "pinhole column and apparent height",
    "05.1": "residual block with vertical-only pooling",
    "06.1": "DAgger mixing rule",
    "06.2": "the K-step BPTT loss (eq. 10, figure 3)",
    "05.2": "experiment: a panorama that wraps around",
    "05.3": "the state-estimation loss of stage 1",
    "06.3": "experiment: the odd part of a CNN",
    "07.1": "experiment: a longer horizon",
    "08.1": "lost messages, as a drone meets them",
}
"""Every graded exercise of the book: id ("NN.k", NN = the notebook's number) -> what is implemented.
The checks of 01.x-04.1 are here; those of the method's core (02.2, 03.2, 05.1, 06.1, 06.2) in
``method_exercises``, those that reach training and perturbed worlds (03.3, 05.3, 08.1) in
``training_exercises``; the open-ended experiments (05.2, 06.3, 07.1) have theirs in
``experiment_exercises``: the check grades the tool the student writes; the experiment done with it
is the student's."""

GRADE_FILE_ENV = "VGAI_LITE_GRADE_FILE"
"""When set (by ``python -m vgai_lite grade``), every check appends its result to this file as a JSON line."""

RESULTS: dict[str, "CheckResult"] = {}
"""The latest result of each exercise checked in this Python session, by id (read by ``score``)."""


def exercises_of(notebook: str) -> list[str]:
    """The exercise ids of notebook ``"NN"`` (e.g. "01" -> ["01.1", "01.2"])."""
    if not (isinstance(notebook, str) and len(notebook) == 2 and notebook.isdigit()):
        raise ValueError(f"notebook must be a two-digit string such as '01', got {notebook!r}")
    return [k for k in EXERCISES if k.startswith(notebook + ".")]


def _record(result: "CheckResult") -> None:
    RESULTS[result.exercise] = result
    path = os.environ.get(GRADE_FILE_ENV)
    if path:
        with open(path, "a") as f:
            f.write(json.dumps({"exercise": result.exercise, "passed": result.passed,
                                "message": result.message}) + "\n")


def score(notebook: str) -> None:
    """Print this notebook's score from the checks run so far in this session, one line per exercise
    (it returns nothing: what a notebook shows of it is the same in JupyterLab and under nbval)."""
    ids = exercises_of(notebook)
    passed = {k: bool(RESULTS.get(k)) for k in ids}
    for k in ids:
        state = "PASSED" if passed[k] else ("NOT PASSED" if k in RESULTS else "NOT RUN")
        print(f"  {k} {EXERCISES[k]:45s} {state}")
    total = sum(passed.values())
    print(f"Score for notebook {notebook}: {total}/{len(ids)}")


def _run(exercise: str, body: Callable[[], tuple[bool, str]]) -> CheckResult:
    try:
        passed, message = body()
    except PermissionError as exc:
        if not str(exc).startswith(LIBRARY_CALL):
            raise
        name = str(exc)[len(LIBRARY_CALL):]
        passed, message = False, (f"your answer calls the library's own `{name}`, the very thing this exercise "
                                  "asks you to write: write it from the equation (other library functions are allowed).")
    except NotImplementedError:
        passed, message = False, "not implemented yet: replace the `raise NotImplementedError` with your code."
    except AnswerMismatch as exc:  # the check's own test failed: say what was expected
        passed, message = False, str(exc)
    except Exception as exc:  # the student's code raised: report it, do not crash the notebook
        tb = traceback.extract_tb(exc.__traceback__)[-1]
        passed, message = False, (f"your function raised {type(exc).__name__}: {exc} "
                                  f"(line {tb.lineno}: {tb.line!r})")
    result = CheckResult(exercise, passed, message)
    _record(result)
    print(result)
    return result


def _as_tensor(got, shape, what: str) -> torch.Tensor:
    if not isinstance(got, torch.Tensor):
        raise AnswerMismatch(f"expected {what} as a torch.Tensor of shape {tuple(shape)}, "
                             f"your function returned a {type(got).__name__}")
    if tuple(got.shape) != tuple(shape):
        raise AnswerMismatch(f"expected {what} of shape {tuple(shape)}, got shape {tuple(got.shape)}")
    return got.detach().to(torch.float64)


def check_potential_gradient(student_fn: Callable) -> CheckResult:
    """Exercise 01.1: ``student_fn(r_ij, rho) -> grad_{r_i} U`` for offsets ``r_ij`` of shape (M, 2).

    U is the paper's potential (eq. 3): 1/||r||^2 - log ||r||^2 inside rho, constant outside.
    """
    student_fn = guarded(student_fn, potential_gradient)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        # rho <= 0.8 and distances on a jittered grid from 0.1 rho to 1.5 rho: every run has offsets
        # beyond rho and between rho and sqrt(rho) (where "||r||^2 <= rho" instead of "||r|| <= rho" errs)
        rho = 0.3 + 0.5 * torch.rand((), generator=g, dtype=torch.float64).item()
        M = 64
        dist = rho * (0.1 + 1.4 * (torch.arange(M, dtype=torch.float64) + torch.rand(M, generator=g, dtype=torch.float64)) / M)
        angle = 2 * torch.pi * torch.rand(M, generator=g, dtype=torch.float64)
        r_ij = torch.stack((dist * angle.cos(), dist * angle.sin()), dim=-1)
        expected = potential_gradient(r_ij, FlockConfig(rho=rho))
        got = _as_tensor(student_fn(r_ij.clone(), rho), expected.shape, "the gradient")
        err = (got - expected).norm(dim=-1)
        tol = 1e-6 + 1e-4 * expected.norm(dim=-1)
        if bool((err <= tol).all()):
            return True, f"matches eq. 3's gradient on {M} random offsets (rho = {rho:.2f} m)."
        k = int((err - tol).argmax())
        hint = ""
        if torch.allclose(got[k], -expected[k], rtol=1e-4):
            hint = " Your sign is flipped: the gradient with respect to r_i, not r_j."
        elif dist[k] > rho:
            hint = " Beyond rho the potential is constant, so its gradient is zero."
        elif torch.allclose(got[k], expected[k] * 2, rtol=1e-3) or torch.allclose(got[k], expected[k] / 2, rtol=1e-3):
            hint = " Off by a factor of 2: d/dr ||r||^2 = 2 r."
        return False, (f"at r_ij = {_fmt(r_ij[k])} (||r_ij|| = {dist[k]:.3f} m, rho = {rho:.2f} m) "
                       f"expected {_fmt(expected[k])}, got {_fmt(got[k])}.{hint}")

    return _run("01.1", body)


def check_flocking_cost(student_fn: Callable) -> CheckResult:
    """Exercise 01.2: ``student_fn(v) -> cost`` for velocities (T, B, N, 2), returning (B,) (eq. 1)."""
    student_fn = guarded(student_fn, flocking_cost, velocity_variance)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        T, B, N = (int(x) for x in torch.randint(2, 12, (3,), generator=g))
        v = 3 * torch.randn(T, B, N, 2, generator=g, dtype=torch.float64) + torch.randn(2, generator=g, dtype=torch.float64)
        expected = flocking_cost(v)
        got = _as_tensor(student_fn(v.clone()), expected.shape, "the cost per swarm")
        if _close(got, expected):
            return True, f"matches eq. 1 on random trajectories (T={T}, B={B}, N={N})."
        k = int((got - expected).abs().argmax())
        ratio = (got[k] / expected[k]).item()
        hint = ""
        for factor, why in ((N, "divide the sum over agents by N (eq. 1 has 1/N)"),
                            (1 / N, "1/N appears once, not twice"),
                            (T, "sum over time, do not average"), (1 / T, "sum over time, do not average")):
            if abs(ratio - factor) < 1e-6 * max(1.0, factor):
                hint = f" Your value is {ratio:.4g} times the expected one: {why}."
        return False, (f"for swarm b={k} of a random trajectory with T={T}, B={B}, N={N} expected "
                       f"{expected[k].item():.6g}, got {got[k].item():.6g}.{hint}")

    return _run("01.2", body)


def _random_swarm_sequence(g: torch.Generator, T: int, N: int, step: float = 0.1):
    """A short random walk of one swarm, dense enough to have links: r (T, N, 2)."""
    r = torch.rand(1, N, 2, generator=g, dtype=torch.float64) * (N ** 0.5) * 0.6
    steps = step * torch.randn(T, 1, N, 2, generator=g, dtype=torch.float64)
    return (r + steps.cumsum(0))[:, 0]


def check_aggregation_sequence(student_fn: Callable) -> CheckResult:
    """Exercise 02.1: ``student_fn(X, S, K) -> Z(t)`` at the last time t = T-1 of a window.

    X (T, N, F) features and S (T, N, N) GSOs at times 0 ... T-1 of one swarm (nothing before 0);
    return Z(T-1) of shape (N, K, F): block k = S(t) S(t-1) ... S(t-k+1) X(t-k) (eq. 6).
    """
    student_fn = guarded(student_fn, aggregation_sequence, AggregationBuffer.push)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        # two windows: one longer than K, one shorter (K > T: blocks from before t = 0 must be zero)
        for short in (False, True):
            passed, message = _one_aggregation_window(student_fn, g, short)
            if not passed:
                return passed, message
        return True, message

    return _run("02.1", body)


def _one_aggregation_window(student_fn, g, short: bool):
    T, N, F = int(torch.randint(3, 7, (1,), generator=g)), int(torch.randint(8, 15, (1,), generator=g)), 3
    K = int(torch.randint(T + 1, T + 4, (1,), generator=g)) if short else int(torch.randint(3, T + 1, (1,), generator=g))
    for _ in range(50):  # a window whose graph changes at every step, so S(t) S(t-1) != S(t)^2
        S = gso(adjacency(_random_swarm_sequence(g, T, N, step=0.3), 1.5))
        if all(not torch.equal(S[t], S[t - 1]) for t in range(1, T)):
            break
    X = torch.randn(T, N, F, generator=g, dtype=torch.float64)
    expected = aggregation_sequence(X[None], S[None], K)[0, -1]
    got = _as_tensor(student_fn(X.clone(), S.clone(), K), expected.shape, "Z(t)")
    if _close(got, expected):
        return True, f"matches eq. 6 on random windows (T={T}, N={N}, F={F}, K={K}: K > T, zeros before t = 0)."
    bad = [k for k in range(K) if not _close(got[:, k], expected[:, k])]
    k = bad[0]
    t = T - 1
    hint = ""
    if k == 0:
        hint = " Block 0 is the agents' own current features X(t)."
    elif t - k < 0:
        hint = (f" Block {k} would need X({t - k}), before the flight began: nothing was sent then, so the block"
                " is zero (careful: X[t - k] with a negative index wraps around to the window's end).")
    elif _close(got[:, k], torch.linalg.matrix_power(S[-1], k) @ X[-1 - k]):
        hint = (" You used S(t)^k; the graph changes over time: block k uses "
                "S(t) S(t-1) ... S(t-k+1).")
    elif _close(got[:, k], torch.linalg.matrix_power(S[-1], k) @ X[-1]):
        hint = " Block k uses the features of k steps ago, X(t-k): information arrives late."
    else:
        prod = X[t - k]
        for s_ in range(t, t - k, -1):  # S(t) applied first: the product in reverse order
            prod = S[s_] @ prod
        if _close(got[:, k], prod):
            hint = (" The product is in reverse order: X(t-k) is first multiplied by S(t-k+1), the graph of"
                    " the step after it was sent, and by S(t) last.")
    return False, (f"block k={k} (of K={K}) differs on a window with T={T}, N={N} (t = {t}): expected "
                   f"row 0 = {_fmt(expected[0, k])}, got {_fmt(got[0, k])}.{hint}")


def check_local_features(student_fn: Callable) -> CheckResult:
    """Exercise 03.1: ``student_fn(r, v, R) -> X`` with r, v (N, 2): the 6 local features (N, 6),
    ordered [sum (v_i - v_j), sum r_ij/|r_ij|^4, sum r_ij/|r_ij|^2] over neighbours within R."""
    student_fn = guarded(student_fn, local_features)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        R = 1.2 + 0.8 * torch.rand(1, generator=g, dtype=torch.float64).item()
        for _ in range(1000):  # a swarm with pairs within R, beyond R, and between sqrt(R) and R
            N = int(torch.randint(5, 20, (1,), generator=g))
            r = _random_swarm_sequence(g, 1, N)[0]
            d = torch.cdist(r, r)[~torch.eye(N, dtype=torch.bool)]
            if (d > R).any() and ((d > R ** 0.5) & (d <= R)).any() and (d <= R ** 0.5).any():
                break
        v = torch.randn(N, 2, generator=g, dtype=torch.float64)
        expected = local_features(r[None], v[None], R)[0]
        got = _as_tensor(student_fn(r.clone(), v.clone(), R), expected.shape, "X")
        # float32 rounding scales with the size of the summed terms, not of their sum (near pairs'
        # 1/|r|^3 terms cancel): the tolerance of each sum is 1e-4 times the sum of its terms' sizes
        d = torch.cdist(r, r)
        A = ((d <= R) & ~torch.eye(N, dtype=torch.bool)).to(r.dtype)
        d = d + torch.eye(N, dtype=r.dtype)  # no 1/0 on the diagonal (A is 0 there)
        sizes = torch.stack(((A * torch.cdist(v, v)).sum(-1), (A / d ** 3).sum(-1), (A / d).sum(-1)), -1)
        tol = 1e-6 + 1e-4 * (sizes.repeat_interleave(2, -1) + expected.abs())
        if bool(((got - expected).abs() <= tol).all()):
            return True, f"matches the 6 local features on a random swarm (N={N}, R={R:.2f} m)."
        i = int(((got - expected).abs() - tol).amax(-1).argmax())
        names = ("sum (v_i - v_j)", "sum r_ij/|r_ij|^4", "sum r_ij/|r_ij|^2")
        wrong = [names[k] for k in range(3) if not ((got[i, 2 * k:2 * k + 2] - expected[i, 2 * k:2 * k + 2]).abs()
                                                    <= tol[i, 2 * k:2 * k + 2]).all()]
        hint = ""
        if not torch.isfinite(got).all():
            hint = " Some values are not finite: leave agent i itself out of its own sums."
        elif torch.allclose(got[i], -expected[i], rtol=1e-6):
            hint = " Sign flipped: r_ij = r_i - r_j and v_i - v_j."
        elif _close(got, local_features(r[None], v[None], 1e9)[0]):
            hint = f" Only neighbours within R = {R:.2f} m count: your sums include every other agent."
        elif _close(got, local_features(r[None], v[None], R ** 0.5)[0]):
            hint = " Compare distances with R, or squared distances with R^2, not squared distances with R."
        return False, (f"agent {i} of a random swarm (N={N}, R={R:.2f} m): wrong {', '.join(wrong)}; "
                       f"expected {_fmt(expected[i])}, got {_fmt(got[i])}.{hint}")

    return _run("03.1", body)


def check_pinhole(student_fn: Callable) -> CheckResult:
    """Exercise 04.1: ``student_fn(theta, d, rcfg) -> (u, height)`` for a drone at bearing ``theta``
    (radians, CCW from +x) and centre distance ``d`` (m): the continuous panorama column u of its
    bearing and its apparent height in rows, 2 f_v (h/2) / (d - body_radius)."""
    student_fn = guarded(student_fn, bearing_to_column)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        rcfg = RenderConfig(view_width=int(torch.randint(8, 64, (1,), generator=g)) * 2,
                            view_height=int(torch.randint(8, 48, (1,), generator=g)) * 2)
        for _ in range(20):
            theta = (2 * torch.rand(1, generator=g, dtype=torch.float64).item() - 1) * math.pi
            d = 0.2 + 3 * torch.rand(1, generator=g, dtype=torch.float64).item()
            u_exp = bearing_to_column(torch.tensor(theta, dtype=torch.float64), rcfg).item()
            h_exp = 2 * rcfg.focal_vertical * (rcfg.body_height / 2) / (d - rcfg.body_radius)
            got = student_fn(theta, d, rcfg)
            if not (isinstance(got, tuple) and len(got) == 2):
                raise AnswerMismatch(f"expected a tuple (u, height), got {type(got).__name__}")
            u, h = (float(x) for x in got)
            cam = int(u_exp // rcfg.view_width)
            if abs(u - u_exp) > 1e-6:
                hint = ""
                if abs((u - u_exp) % rcfg.view_width) < 1e-6 or abs((u_exp - u) % rcfg.view_width) < 1e-6:
                    hint = " Right offset within a camera, wrong camera: the order is front, right, back, left."
                elif abs(2 * rcfg.view_width * (cam + 0.5) - u - u_exp) < 1e-6:
                    hint = " Mirrored within the camera: columns run left to right, i.e. clockwise."
                return False, (f"for theta = {math.degrees(theta):.1f}° (camera {cam}, W = {rcfg.view_width}) "
                               f"expected u = {u_exp:.4f}, got {u:.4f}.{hint}")
            if abs(h - h_exp) > 1e-6 * max(1.0, h_exp):
                hint = " Use the distance to the body's near side, d - body_radius." if abs(
                    h - 2 * rcfg.focal_vertical * (rcfg.body_height / 2) / d) < 1e-6 else ""
                return False, (f"for d = {d:.3f} m (H = {rcfg.view_height}, vertical FOV "
                               f"{rcfg.vertical_fov_deg}°) expected height {h_exp:.4f} rows, got {h:.4f}.{hint}")
        return True, "columns and heights match the pinhole model on 20 random drones and cameras."

    return _run("04.1", body)
