"""Checks of the book's open-ended experiments: the student writes a tool, the check grades it, and
the experiment the notebook then runs with it is the student's to extend and interpret.

Introduced in notebook 05. Like ``exercises``, each check runs the student's code on fresh random
inputs against a property that defines the tool, never raises, and prints what went wrong.

  05.2  a convolution along the panorama's columns that wraps around (the panorama is a circle)
  06.3  the odd part of a CNN in its motion channels (notebook 06)
  07.1  the velocity variance at any horizon of a flight (what eq. 1 hides late in a flight)
"""

from __future__ import annotations

from typing import Callable

import torch

from ..flocking import velocity_variance
from .exercises import AnswerMismatch, CheckResult, _as_tensor, _close, _fresh_generator, _run
from .library_guard import guarded


def check_circular_conv(student_cls: Callable) -> CheckResult:
    """Exercise 05.2: ``student_cls(c_in, c_out)`` builds an nn.Module mapping (M, c_in, H, W) to
    (M, c_out, H, W): a 1x3 convolution along the columns whose padding wraps around, so that turning
    the drone (rolling the panorama's columns) rolls its output exactly, and a column sees only its
    two neighbours, across the seam between the last column and the first too."""
    def body():
        g = _fresh_generator()
        for _ in range(3):
            c_in, c_out = (int(x) for x in torch.randint(1, 5, (2,), generator=g))
            H, W = int(torch.randint(3, 6, (1,), generator=g)), int(torch.randint(8, 40, (1,), generator=g))
            layer = student_cls(c_in, c_out)
            if not isinstance(layer, torch.nn.Module):
                raise AnswerMismatch(f"expected an nn.Module, got {type(layer).__name__}")
            x = torch.randn(2, c_in, H, W, generator=g)
            with torch.no_grad():
                y = _as_tensor(layer(x), (2, c_out, H, W), "the output")
                k = int(torch.randint(1, W, (1,), generator=g))
                rolled = _as_tensor(layer(torch.roll(x, k, dims=-1)), (2, c_out, H, W), "the output")
                if (rolled - torch.roll(y, k, dims=-1)).abs().max() > 1e-5:
                    return False, (f"rolling the input's {W} columns by {k} did not roll the output by {k}: "
                                   "pad the columns circularly (the first column's left neighbour is the last).")
                x2 = x.clone()
                x2[..., 0] += 3.0
                change = (_as_tensor(layer(x2), y.shape, "the output") - y).abs().amax(dim=(0, 1, 2))
                x3 = x.clone()
                x3[:, :, 0] += 3.0  # the first row only
                rows = (_as_tensor(layer(x3), y.shape, "the output") - y).abs().amax(dim=(0, 1, 3))
            if rows[1:].max() > 1e-6:
                return False, ("changing the first row changed other rows: the convolution runs along the columns "
                               "only (a 1x3 kernel), and a row is not a circle: never wrap the rows.")
            near = {W - 1, 0, 1}
            if any(change[j] > 1e-6 for j in range(W) if j not in near):
                return False, "changing column 0 changed columns other than its two neighbours (the last column and column 1): keep the kernel 1x3."
            if change[W - 1] <= 1e-6 and change[1] <= 1e-6:
                return False, "a column must see its neighbours: column 0's change reached neither column 1 nor the last."
        return True, "shapes kept, rolling the panorama rolls the output, and the first and last columns are neighbours."

    return _run("05.2", body)


def check_odd_part(student_fn: Callable) -> CheckResult:
    """Exercise 06.3: ``student_fn(f, images) -> x_odd`` for any function f of images (M, C, H, W)
    -> (M, F), whose second half of channels is the motion D: the odd part
    (f([I, D]) - f([I, -D])) / 2, exactly 0 when nothing moves (D = 0)."""
    def body():
        g = _fresh_generator()
        C2, H, W, F = 2 * int(torch.randint(1, 3, (1,), generator=g)), 4, 16, 5
        net = torch.nn.Sequential(torch.nn.Conv2d(C2, 3, 3, padding=1), torch.nn.Tanh(), torch.nn.Flatten(),
                                  torch.nn.Linear(3 * H * W, F))
        with torch.no_grad():
            for p in net.parameters():
                p.copy_(torch.randn(p.shape, generator=g) * 0.3 + 0.1)
            f = lambda im: net(im)
            images = torch.randn(3, C2, H, W, generator=g)
            c = C2 // 2
            mirrored = torch.cat((images[:, :c], -images[:, c:]), dim=1)
            want = (f(images) - f(mirrored)) / 2
            got = _as_tensor(student_fn(f, images.clone()), want.shape, "the odd part")
            if (got - want).abs().max() > 1e-5:
                if (got + want).abs().max() < 1e-5:
                    return False, "the sign is flipped: the odd part is (f([I, D]) - f([I, -D])) / 2."
                if (got - (f(images) + f(mirrored)) / 2).abs().max() < 1e-5:
                    return False, "that is the even part (the sum); the odd part is the difference."
                return False, ("on random images and a random network your odd part differs from "
                               "(f([I, D]) - f([I, -D])) / 2: negate only the second half of the channels.")
            still = images.clone()
            still[:, c:] = 0
            at_rest = _as_tensor(student_fn(f, still), want.shape, "the odd part")
            if at_rest.abs().max() > 0:
                return False, "with D = 0 (nothing moves) the odd part must be exactly 0."
        return True, "the odd part of a random network, exactly 0 when nothing moves."

    return _run("06.3", body)


def check_variance_at(student_fn: Callable) -> CheckResult:
    """Exercise 07.1: ``student_fn(v, Ts, seconds) -> (B,)``: the velocity variance
    (1/N) sum_i ||v_i - vbar||^2 (eq. 1's summand) of each flight at time ``seconds``, the step
    round(seconds / Ts) of velocities v (T, B, N, 2)."""
    student_fn = guarded(student_fn, velocity_variance)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        T, B, N = int(torch.randint(60, 120, (1,), generator=g)), 3, int(torch.randint(3, 9, (1,), generator=g))
        v = torch.randn(T, B, N, 2, generator=g, dtype=torch.float64)
        Ts = 0.01
        # times a student types (0.29 s) whose quotient by Ts is not a whole number in floating point:
        # 0.29 / 0.01 = 28.999999999999996 (int() picks step 28) and 0.07 / 0.01 = 7.000000000000001
        below = [k for k in range(1, T) if round(k * Ts, 10) / Ts < k]
        above = [k for k in range(1, T) if round(k * Ts, 10) / Ts > k]
        pick = lambda ks: ks[int(torch.randint(0, len(ks), (1,), generator=g))]
        for step in (0, T - 1, pick(below), pick(above)):
            want = velocity_variance(v)[step]
            got = _as_tensor(student_fn(v.clone(), Ts, round(step * Ts, 10)), (B,), "one variance per flight")
            if not _close(got, want):
                hint = ""
                if _close(got, want * N / (N - 1)):
                    hint = " Divide by N, not N - 1."
                elif _close(got, (v[step] ** 2).sum(-1).mean(-1)):
                    hint = " Subtract the swarm's mean velocity first."
                elif any(_close(got, velocity_variance(v)[k]) for k in (step - 1, step + 1) if 0 <= k < T):
                    hint = (f" That is the variance one step off: {step * Ts:.2f} / {Ts} = {step * Ts / Ts!r} in "
                            "floating point; round it to the nearest step, round(seconds / Ts), do not truncate.")
                return False, f"at {step * Ts:.2f} s (step {step}) expected {want.tolist()}, got {got.tolist()}.{hint}"
        return True, "the variance of every flight at any time, as eq. 1 sums it."

    return _run("07.1", body)
