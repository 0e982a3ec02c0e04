"""Checks of the exercises that reach training and perturbed worlds: the state-estimation loss of
stage 1 (05.3), DAgger's training loop (03.3) and lost messages as a drone meets them (08.1).

Introduced in notebook 03. Built like ``exercises``: fresh random inputs on every run, a property or
the library's own implementation as the reference, a hint for each mistake students make, and the
library's own answer refused (``library_guard``).
"""

from __future__ import annotations

from typing import Callable

import torch
import torch.nn.functional as nnf
from torch import nn

from ..dagnn_training import collect, train_dagnn
from ..imitation import EpisodeStore, fly_dagger
from ..vgai_training import estimation_loss
from .exercises import AnswerMismatch, CheckResult, _as_tensor, _close, _fresh_generator, _run
from .library_guard import guarded
from .method_exercises import _random_adjacency
from .perturbations import DroppedLinks


# ---------------------------------------------------------------------------------------------
# 05.3: the state-estimation loss of stage 1

def check_estimation_loss(student_fn: Callable) -> CheckResult:
    """Exercise 05.3: ``student_fn(X, head, x_exact, mean, std) -> loss``: the state-estimation loss
    of stage 1 (``vgai_training.estimation_loss``). ``X`` (M, F) the CNN's features of M agents'
    images, ``head`` the linear aux head (F -> 6), ``x_exact`` (M, 6) the exact local features,
    ``mean``, ``std`` (6,) their scale over the training flights. The head reads standardised
    features: the loss is the L1 distance between head(X) and (x_exact - mean) / std, the mean over
    agents and the six features, differentiable down to X."""
    student_fn = guarded(student_fn, estimation_loss)  # the library's own answer does not count

    def body():
        g = _fresh_generator()
        M, F = int(torch.randint(20, 40, (1,), generator=g)), int(torch.randint(4, 9, (1,), generator=g))
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(int(torch.randint(0, 2 ** 31, (1,), generator=g)))
            head = nn.Linear(F, 6).double()
        X = torch.randn(M, F, generator=g, dtype=torch.float64)
        # features of very different sizes (the repulsion sums reach hundreds), as the exact ones have
        std = torch.exp(torch.randn(6, generator=g, dtype=torch.float64) * 2)
        mean = torch.randn(6, generator=g, dtype=torch.float64) * std
        x_exact = mean + std * torch.randn(M, 6, generator=g, dtype=torch.float64)
        want = nnf.l1_loss(head(X), (x_exact - mean) / std)
        Xg = X.clone().requires_grad_(True)
        got = student_fn(Xg, head, x_exact.clone(), mean.clone(), std.clone())
        if not (isinstance(got, torch.Tensor) and got.numel() == 1):
            raise AnswerMismatch(f"expected the loss as a one-number tensor, got {type(got).__name__}"
                                 + (f" of shape {tuple(got.shape)}" if isinstance(got, torch.Tensor) else ""))
        value = got.detach().reshape(())
        if not _close(value, want.detach()):
            pred = head(X).detach()
            hint = ""
            if _close(value, nnf.l1_loss(pred, x_exact).detach()):
                hint = (" That compares the head's output with the raw features: the head reads standardised "
                        "ones, (x - mean) / std, so that the large repulsion sums do not drown the velocities.")
            elif _close(value, nnf.l1_loss(pred * std + mean, x_exact).detach()):
                hint = (" That un-standardises the prediction instead: the loss is then dominated by the features "
                        "with the largest spread; compare in standardised units.")
            elif _close(value, nnf.mse_loss(pred, (x_exact - mean) / std).detach()):
                hint = " That is the squared error; the book's losses are L1, as eq. 10."
            elif _close(value, (pred - (x_exact - mean) / std).abs().sum().detach()):
                hint = " Take the mean over agents and features (F.l1_loss), not the sum."
            return False, (f"on {M} agents with F = {F} features expected the loss {want.item():.6g}, "
                           f"got {value.item():.6g}.{hint}")
        (grad,) = torch.autograd.grad(got.reshape(()), Xg, allow_unused=True)
        if grad is None:
            return False, "no gradient reaches the features X: do not detach them (the CNN learns through this loss)."
        Xr = X.clone().requires_grad_(True)
        (want_grad,) = torch.autograd.grad(nnf.l1_loss(head(Xr), (x_exact - mean) / std), Xr)
        if not torch.allclose(grad.to(want_grad.dtype), want_grad, rtol=1e-4, atol=1e-9):
            return False, "the loss's gradient with respect to X is not the L1 loss's: compute it from head(X) itself."
        return True, "the L1 distance in standardised units, with its gradient down to the CNN's features."

    return _run("05.3", body)


# ---------------------------------------------------------------------------------------------
# 08.1: lost messages, as a drone would meet them

def check_lost_messages(student_fn: Callable) -> CheckResult:
    """Exercise 08.1: ``student_fn(A, p, generator) -> A_heard``: the links (B, N, N) that carried a
    message this exchange, A_ij = 1 when i hears j. Each message is lost independently with
    probability p: i may miss j while j hears i. The draws come from ``generator`` (a run is
    reproduced by seeding it), the input is left as it was, and p = 0 changes nothing."""
    student_fn = guarded(student_fn, DroppedLinks.links)  # the library's own answer does not count

    def body():
        g = _fresh_generator()
        B, N = 64, int(torch.randint(5, 10, (1,), generator=g))
        A = ((_random_adjacency(g, B, N) + torch.roll(torch.eye(N), 1, 0) + torch.roll(torch.eye(N), -1, 0)) > 0).float()
        A = A * (1 - torch.eye(N))
        for p in (0.0, 0.25, 0.6, 1.0):
            seed = int(torch.randint(0, 2 ** 31, (1,), generator=g))
            before = A.clone()
            got = student_fn(A, p, torch.Generator().manual_seed(seed))
            if not torch.equal(A, before):
                return False, "your function changed its input A in place: return a new tensor, the graph itself is not lost."
            got = _as_tensor(got, A.shape, "the links that carried a message")
            if not ((got == 0) | (got == A)).all():
                return False, "each entry must be the link as it was (a message heard) or 0 (lost): nothing else, no new links."
            if p == 0 and not torch.equal(got, A.double()):
                return False, "with p = 0 no message is lost: the links must come back unchanged."
            kept = float(got.sum() / A.sum())
            if abs(kept - (1 - p)) > 0.06:
                return False, f"with p = {p} your function kept {kept:.0%} of the messages; each is lost with probability p."
            if 0 < p < 1:
                both = (A * A.transpose(-1, -2)).bool()
                one_way = (got.bool() ^ got.transpose(-1, -2).bool()) & both
                share = float(one_way.sum() / both.sum())
                if share < p * (1 - p):  # independent directions: about 2 p (1 - p) of the pairs hear one way
                    return False, ("a lost message is one direction of a link: when i misses j, j may still hear i. "
                                   "Draw one coin per message (i, j), not one per pair.")
                rows = A.sum(-1) >= 3  # an agent's messages are lost one by one, not all at once
                heard = got.sum(-1)
                all_or_none = ((heard == 0) | (heard == A.sum(-1)))[rows].double().mean()
                if all_or_none > 0.75:
                    return False, ("an agent lost all of its messages or none: each message (i, j) is lost on its own, "
                                   "so an agent with several neighbours usually hears some of them.")
                torch.manual_seed(seed + 1)  # the global generator stirred between the two calls
                again = student_fn(A, p, torch.Generator().manual_seed(seed))
                if not torch.equal(_as_tensor(again, A.shape, "the links"), got):
                    return False, ("two calls with generators seeded alike lost different messages: draw from the "
                                   "`generator` argument, not from torch's global random state.")
        return True, "each message lost independently with probability p, reproducibly, nothing changed at p = 0."

    return _run("08.1", body)


# ---------------------------------------------------------------------------------------------
# 03.3: the DAgger training loop

class _LinearPolicy:
    """u_i = W [r_i - mean r, v_i, 1]: a learner the check can fit in closed form; (r, v) (B, N, 2) -> (B, N, 2)."""

    def __init__(self):
        self.W = torch.zeros(5, 2, dtype=torch.float64)

    @staticmethod
    def features(r, v):
        return torch.cat((r - r.mean(1, keepdim=True), v, torch.ones_like(r[..., :1])), dim=-1)

    def __call__(self, r, v):
        return self.features(r, v) @ self.W


def check_dagger_training(student_fn: Callable) -> CheckResult:
    """Exercise 03.3: ``student_fn(learner, fit, expert, step, starts, steps, p, generator) -> data``:
    DAgger's training loop. ``starts`` is a list of (r0, v0), one per round, each (B, N, 2). Round k
    flies ``steps`` steps from starts[k]: at each, record the state and the expert's label u* =
    expert(r, v), and apply the learner's action learner(r, v) instead of u* with probability p, one
    coin per swarm and step from ``generator`` (round 0 flies the expert alone: the learner has learned
    nothing yet). After each round, ``fit(data)`` fits the learner on the data of every round so far.
    ``data`` is a dict of lists "r", "v", "u", one (B, N, 2) tensor per visited step; return it."""
    student_fn = guarded(student_fn, fly_dagger, EpisodeStore.fly, collect, train_dagnn)  # the library's own loop

    def body():
        g = _fresh_generator()
        B, N, steps, rounds, p = 32, int(torch.randint(4, 7, (1,), generator=g)), 10, 3, 0.4
        a = 0.5 + float(torch.rand((), generator=g))
        expert = lambda r, v: -a * v - 0.3 * torch.tanh(3 * (r - r.mean(1, keepdim=True)))  # not linear: the learner errs
        step = lambda r, v, u: (r + 0.1 * v, v + 0.1 * u)
        starts = [(torch.randn(B, N, 2, generator=g, dtype=torch.float64),
                   torch.randn(B, N, 2, generator=g, dtype=torch.float64)) for _ in range(rounds)]
        seed = int(torch.randint(0, 2 ** 31, (1,), generator=g))

        def run(stir: int):
            learner, fitted = _LinearPolicy(), []

            def fit(data):
                fitted.append((len(data["r"]), learner.W.clone()))
                X = torch.cat([learner.features(r, v).reshape(-1, 5) for r, v in zip(data["r"], data["v"])])
                U = torch.cat([u.reshape(-1, 2) for u in data["u"]])
                learner.W = torch.linalg.solve(X.T @ X + 1e-6 * torch.eye(5, dtype=X.dtype), X.T @ U)

            torch.manual_seed(seed + stir)  # the global generator in another state at each run
            data = student_fn(learner, fit, expert, step, [(r.clone(), v.clone()) for r, v in starts], steps, p,
                              torch.Generator().manual_seed(seed))
            return learner, fitted, data

        learner, fitted, data = run(1)
        if not (isinstance(data, dict) and all(isinstance(data.get(k), list) for k in "rvu")):
            raise AnswerMismatch('expected the data back as a dict of lists "r", "v", "u"')
        if [n for n, _ in fitted] != [steps * (k + 1) for k in range(rounds)]:
            return False, (f"fit saw {[n for n, _ in fitted] or 'no'} states at its calls; expected one call after each of "
                           f"the {rounds} rounds, on the data of every round so far ({[steps * (k + 1) for k in range(rounds)]}): "
                           "DAgger aggregates, and fits after every round.")
        if not all(len(data[k]) == rounds * steps for k in "rvu"):
            return False, f'expected {rounds} x {steps} entries in each of "r", "v", "u", one per visited step.'
        if not all(torch.equal(u, expert(r, v)) for r, v, u in zip(data["r"], data["v"], data["u"])):
            return False, "every recorded state is labelled with the expert's action at that state, whoever flew it."
        r, v = starts[0]
        for t in range(steps):
            if not (torch.equal(data["r"][t], r) and torch.equal(data["v"][t], v)):
                return False, ("round 0 must fly the expert alone (p = 0): the learner has learned nothing yet, and "
                               "its states would teach the fit nothing about the expert's.")
            r, v = step(r, v, expert(r, v))
        followed, coins = 0, 0
        for k in range(1, rounds):
            W = fitted[k][1]  # the learner as it flew round k: fitted after round k - 1
            if not (torch.equal(data["r"][k * steps], starts[k][0]) and torch.equal(data["v"][k * steps], starts[k][1])):
                return False, f"round {k} must start from starts[{k}]."
            for t in range(k * steps, (k + 1) * steps - 1):
                r, v, v1 = data["r"][t], data["v"][t], data["v"][t + 1]
                u = (v1 - v) / 0.1
                u_l = _LinearPolicy.features(r, v) @ W
                is_l = ((u - u_l).abs() < 1e-9).all(-1).all(-1)
                is_e = ((u - data["u"][t]).abs() < 1e-9).all(-1).all(-1)
                if not (is_l | is_e).all():
                    return False, ("each swarm applies either the learner's or the expert's action at a step, as a whole "
                                   "(one coin per swarm and step), and flies on from the state it reached.")
                followed, coins = followed + int((is_l & ~is_e).sum()), coins + B
        if abs(followed / coins - p) > 0.08:
            return False, f"with p = {p} your swarms followed the learner {followed / coins:.0%} of the time after round 0."
        _, _, again = run(2)
        if not all(torch.equal(x, y) for k in "rvu" for x, y in zip(data[k], again[k])):
            return False, ("two runs with generators seeded alike differ: draw the coins from the `generator` argument, "
                           "not from torch's global random state.")
        r, v = torch.randn(B, N, 2, generator=g, dtype=torch.float64), torch.randn(B, N, 2, generator=g, dtype=torch.float64)
        err = float((learner(r, v) - expert(r, v)).pow(2).mean().sqrt() / expert(r, v).pow(2).mean().sqrt())
        if err > 0.3:
            return False, f"the trained learner is off the expert by {err:.0%} on fresh states: fit it after every round."
        return True, (f"{rounds} rounds, the expert alone first, then DAgger's mixture, every round's data kept and fitted; "
                      f"the trained learner is within {err:.0%} of the expert on fresh states.")

    return _run("03.3", body)
