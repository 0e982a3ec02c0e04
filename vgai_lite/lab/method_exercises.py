"""Checks of the exercises on what makes the method: the GSO's normalisation (02.2), DAgger's data
aggregation (03.2), the residual block of the CNN (05.1), DAgger's coin (06.1) and the K-step BPTT
loss (06.2); those that reach training and perturbed worlds (03.3, 05.3, 08.1) are in
``training_exercises``.

Introduced in notebook 02. Built like ``exercises``: fresh random inputs on every run, a property or
the library's own implementation as the reference, a hint for each mistake students make, never a
raise. Each check's docstring says what it asks for.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Callable

import torch
import torch.nn.functional as nnf
from torch import nn

from ..aggregation import aggregation_sequence
from .exercises import AnswerMismatch, CheckResult, _as_tensor, _close, _fresh_generator, _run
from .library_guard import guarded
from ..graphs import gso
from ..dagnn_training import collect
from ..imitation import EpisodeStore, dagger_mix, fly_dagger
from ..models import ResidualBlock
from ..vgai_training import bptt_loss, window_action_loss


# ---------------------------------------------------------------------------------------------
# 02.2: the symmetric normalised GSO

def _random_adjacency(g: torch.Generator, B: int, N: int) -> torch.Tensor:
    """Symmetric 0/1 adjacencies (B, N, N) without self-loops, of mixed degrees, each with an isolated agent.
    Each graph has an edge between two drones of different degrees (drawn again until it has), so that an
    answer that normalises by one side only, or by rows, cannot pass on a graph where that happens to agree."""
    A = torch.zeros(B, N, N, dtype=torch.float64)
    todo = torch.ones(B, dtype=torch.bool)
    while todo.any():
        n = int(todo.sum())
        p = 0.15 + 0.6 * torch.rand(n, 1, 1, generator=g, dtype=torch.float64)
        a = (torch.rand(n, N, N, generator=g, dtype=torch.float64) < p).double().triu(1)
        a = a + a.transpose(1, 2)
        lonely = torch.randint(0, N, (n,), generator=g)
        a[torch.arange(n), lonely, :] = 0
        a[torch.arange(n), :, lonely] = 0
        A[todo] = a
        deg = A.sum(-1)
        todo = ~((A > 0) & (deg[:, :, None] != deg[:, None, :])).flatten(1).any(1)
    return A


def check_sym_gso(student_fn: Callable) -> CheckResult:
    """Exercise 02.2: ``student_fn(A) -> S`` for adjacencies A (B, N, N): the symmetric normalised
    graph shift operator S = D^-1/2 A D^-1/2, D = diag(degrees), an isolated drone's row and
    column zero (its degree 0 must not give 0/0)."""
    student_fn = guarded(student_fn, gso)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        B, N = int(torch.randint(3, 7, (1,), generator=g)), int(torch.randint(6, 14, (1,), generator=g))
        A = _random_adjacency(g, B, N)
        want = gso(A, "sym_normalized")
        got = _as_tensor(student_fn(A.clone()), want.shape, "S")
        if _close(got, want):
            return True, f"S = D^-1/2 A D^-1/2 on {B} random graphs of {N} drones, isolated drones included."
        deg = A.sum(-1)
        hint = ""
        if not torch.isfinite(got).all():
            hint = (" Some entries are NaN or infinite: an isolated drone has degree 0, and 1/sqrt(0) is"
                    " infinite; give it a zero row and column (e.g. clamp the degree to at least 1).")
        elif _close(got, A / deg.clamp(min=1)[..., None]):
            hint = " That is D^-1 A (the row-normalised GSO, the neighbours' mean): it is not symmetric."
        elif _close(got, gso(A + torch.eye(N, dtype=A.dtype), "sym_normalized")):
            hint = " You added self-loops: A here has none and S_ii = 0."
        elif _close(got, A * deg.clamp(min=1).rsqrt()[..., None, :]) or _close(got, A * deg.clamp(min=1).rsqrt()[..., None]):
            hint = " Normalise both sides: D^-1/2 on the left (rows) and on the right (columns)."
        elif _close(got, A / deg.clamp(min=1).sqrt().sum(-1, keepdim=True)[..., None]):
            hint = " D is diagonal: each entry S_ij = A_ij / sqrt(d_i d_j), not one number for the whole graph."
        b, i, j = (int(x) for x in torch.nonzero(~torch.isclose(got.to(want.dtype), want, rtol=1e-4, atol=1e-6))[0])
        return False, (f"graph {b}, entry ({i}, {j}) with degrees d_i = {int(deg[b, i])}, d_j = {int(deg[b, j])}: "
                       f"expected {want[b, i, j].item():.4g}, got {got[b, i, j].item():.4g}.{hint}")

    return _run("02.2", body)


# ---------------------------------------------------------------------------------------------
# 03.2: one DAgger round's data aggregation

def _toy_policies(g: torch.Generator):
    """Two different linear policies of (r, v) and a step of double-integrator dynamics (Ts = 0.1)."""
    a, b = (0.5 + torch.rand(2, generator=g, dtype=torch.float64)).tolist()
    expert = lambda r, v: -a * v - 0.3 * (r - r.mean(1, keepdim=True))
    learner = lambda r, v: -0.2 * b * v + 0.1
    step = lambda r, v, u: (r + 0.1 * v, v + 0.1 * u)
    return expert, learner, step


def _expected_round(data, expert, learner, mix, step, r0, v0, steps):
    r, v = r0, v0
    new = {"r": [], "v": [], "u": []}
    for _ in range(steps):
        u_star = expert(r, v)
        new["r"].append(r), new["v"].append(v), new["u"].append(u_star)
        r, v = step(r, v, mix(learner(r, v), u_star))
    return {k: data[k] + new[k] for k in data}


def check_dagger_round(student_fn: Callable) -> CheckResult:
    """Exercise 03.2: ``student_fn(data, learner, expert, mix, step, r0, v0, steps) -> data``: one
    DAgger round. ``data`` holds lists "r", "v", "u" of earlier rounds' states and labels, one
    (B, N, 2) tensor per visited step. From (r0, v0) fly ``steps`` steps; at each, record the state
    and label it with the expert's action u* = expert(r, v), then apply
    mix(learner(r, v), u*) (DAgger's coin: the learner flies with probability p) through
    ``step(r, v, u) -> (r, v)``. Return the data of every round: the old entries first, then the new."""
    student_fn = guarded(student_fn, fly_dagger, EpisodeStore.fly, collect)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        B, N, steps, p = 3, int(torch.randint(3, 7, (1,), generator=g)), int(torch.randint(6, 12, (1,), generator=g)), 0.5
        expert, learner, step = _toy_policies(g)
        old = int(torch.randint(2, 5, (1,), generator=g))
        data = {k: [torch.randn(B, N, 2, generator=g, dtype=torch.float64) for _ in range(old)] for k in "rvu"}
        r0, v0 = torch.randn(B, N, 2, generator=g, dtype=torch.float64), torch.randn(B, N, 2, generator=g, dtype=torch.float64)
        seed = int(torch.randint(0, 2 ** 31, (1,), generator=g))

        def mixer():
            gen = torch.Generator().manual_seed(seed)
            return lambda u_l, u_e: dagger_mix(u_l, u_e, p, gen)

        want = _expected_round({k: list(x) for k, x in data.items()}, expert, learner, mixer(), step, r0, v0, steps)
        got = student_fn({k: list(x) for k, x in data.items()}, learner, expert, mixer(), step, r0.clone(), v0.clone(), steps)
        if not (isinstance(got, dict) and all(isinstance(got.get(k), list) for k in "rvu")):
            raise AnswerMismatch('expected the data back as a dict of lists "r", "v", "u"')
        if len(got["r"]) == steps and old:
            return False, ("the round's data replaced the earlier rounds': DAgger aggregates, keep every earlier "
                           "state and label and append the new ones.")
        if not all(len(got[k]) == old + steps for k in "rvu"):
            return False, (f'expected {old} earlier + {steps} new entries in each of "r", "v", "u", got '
                           f'{[len(got[k]) for k in "rvu"]}: one entry per visited step.')
        if not all(torch.equal(got[k][i], data[k][i]) for k in "rvu" for i in range(old)):
            return False, "the earlier rounds' entries changed or moved: keep them first, as they were."
        new = {k: torch.stack([_as_tensor(x, (B, N, 2), f'an entry of "{k}"') for x in got[k][old:]]) for k in "rvu"}
        exp = {k: torch.stack(want[k][old:]) for k in "rvu"}
        if _close(new["r"], exp["r"]) and _close(new["v"], exp["v"]):
            if _close(new["u"], exp["u"]):
                return True, f"{steps} visited states, each labelled with the expert's action, after {old} earlier entries."
            applied = torch.stack([mixer()(learner(r, v), expert(r, v)) for r, v in zip(exp["r"], exp["v"])])
            hint = (" Those are the actions applied: label every state with the expert's action u*, also where "
                    "the learner flew.") if _close(new["u"], applied) else ""
            return False, f"the states are right, their labels are not.{hint}"
        expert_only = _expected_round({k: [] for k in "rvu"}, expert, learner, lambda u_l, u_e: u_e, step, r0, v0, steps)
        hint = ""
        if _close(new["r"], torch.stack(expert_only["r"])) and _close(new["v"], torch.stack(expert_only["v"])):
            hint = " These are the expert's own flights: the learner must fly where the coin says, apply mix(learner(r, v), u*)."
        elif _close(new["r"][:-1], exp["r"][1:]):
            hint = " Off by one step: record the state the action is chosen in, before stepping."
        return False, f"the visited states differ from the flight under DAgger's mixture.{hint}"

    return _run("03.2", body)


# ---------------------------------------------------------------------------------------------
# 05.1: the residual block

def _column_reach(block, x: torch.Tensor) -> int:
    """How many columns to each side a change of one column (in the middle) reaches, (M, C, H, W)."""
    j = x.shape[-1] // 2
    x2 = x.clone()
    x2[..., j] += 5.0
    with torch.no_grad():
        change = (block(x2) - block(x)).abs().amax(dim=(0, 1, 2))
    cols = [c for c in range(x.shape[-1]) if change[c] > 1e-6]
    return max(abs(c - j) for c in cols) if cols else -1


def _excite(block, g: torch.Generator) -> None:
    """Set every convolution's weights and biases to small positive values (drawn from ``g``)."""
    with torch.no_grad():
        for m in block.modules():
            if isinstance(m, nn.Conv2d):
                m.weight.copy_(0.05 + 0.25 * torch.rand(m.weight.shape, generator=g))
                if m.bias is not None:
                    m.bias.copy_(0.05 + 0.05 * torch.rand(m.bias.shape, generator=g))


def _block_shape_failure(y, x, want, pool):
    H, W = x.shape[-2:]
    hint = ""
    if y.ndim == 4 and y.shape[-1] != W:
        hint = " The width changed: pool along the rows only, e.g. nn.AvgPool2d((pool, 1))."
    elif y.ndim == 4 and y.shape[-2] == H and pool > 1:
        hint = " The rows were not pooled."
    elif y.ndim == 4 and y.shape[-2] != H // pool:
        hint = " Pad the 3x3 convolutions (padding=1) so that they keep the size."
    return False, f"for input {tuple(x.shape)} with pool={pool} expected output {want}, got {tuple(y.shape)}.{hint}"


def _what_is_left(block, x, c, pool):
    """With the 3x3 convolutions zeroed and a 1x1 skip set to the identity: None if what is left is
    pool_rows(relu(x)), else the failure."""
    convs = [m for m in block.modules() if isinstance(m, nn.Conv2d)]
    wide = [m for m in convs if tuple(m.kernel_size) == (3, 3)]
    if len(wide) != 2:
        return False, (f"expected two 3x3 nn.Conv2d layers in the block, found {len(wide)}: use "
                       "nn.Conv2d(..., 3, padding=1) for both convolutions.")
    with torch.no_grad():
        for m in wide:
            m.weight.zero_()
            if m.bias is not None:
                m.bias.zero_()
        for m in convs:
            if tuple(m.kernel_size) == (1, 1) and m.in_channels == m.out_channels == c:
                m.weight.copy_(torch.eye(c)[:, :, None, None])
                if m.bias is not None:
                    m.bias.zero_()
        left, rows = block(x), x.unflatten(2, (x.shape[2] // pool, pool))
    if torch.allclose(left, torch.relu(rows).mean(3), atol=1e-5):
        return None
    hint = ""
    if left.abs().max() < 1e-6:
        hint = " Nothing is left: the skip connection (adding the input back) is missing."
    elif torch.allclose(left, torch.relu(rows).amax(3), atol=1e-5):
        hint = " That is max pooling: the block averages the rows (nn.AvgPool2d((pool, 1)))."
    elif torch.allclose(left, torch.relu(rows.mean(3)), atol=1e-5):
        hint = " The ReLU comes before the pooling: pool_rows(relu(... + skip x))."
    elif torch.allclose(left, rows.mean(3), atol=1e-5):
        hint = " The ReLU after the sum is missing: pool_rows(relu(conv2(...) + skip x))."
    return False, ("with its 3x3 convolutions set to zero a residual block leaves pool_rows(relu(x)) "
                   f"(c_in = c_out = {c}, pool = {pool}); yours differs.{hint}")


def check_residual_block(student_cls: Callable) -> CheckResult:
    """Exercise 05.1: ``student_cls(c_in, c_out, pool)`` builds an nn.Module whose forward maps
    (M, c_in, H, W) to (M, c_out, H / pool, W): two 3x3 convolutions (nn.Conv2d) with a skip
    connection (the identity when c_in = c_out, else a 1x1 convolution), a ReLU, then average
    pooling of ``pool`` rows into one, the columns untouched:
    y = pool_rows(relu(conv2(relu(conv1 x)) + skip x)).

    Tested as behaviour, whatever the layout: output shapes; a column reaches exactly two columns to
    each side (two 3x3 convolutions, not one); and with the 3x3 convolutions' weights and biases
    zero (a 1x1 skip set to the identity), what is left is pool_rows(relu(x)): the skip is there,
    the ReLU comes before the pooling, and the pooling averages."""
    def body():
        g = _fresh_generator()
        for c_in, c_out in ((2, 2), (int(torch.randint(1, 4, (1,), generator=g)), int(torch.randint(4, 7, (1,), generator=g)))):
            pool = int(torch.randint(2, 4, (1,), generator=g))
            H, W, M = pool * int(torch.randint(1, 4, (1,), generator=g)), int(torch.randint(12, 40, (1,), generator=g)), 3
            block = student_cls(c_in, c_out, pool)
            if not isinstance(block, nn.Module):
                raise AnswerMismatch(f"expected the block to be an nn.Module, got {type(block).__name__}")
            x = torch.randn(M, c_in, H, W, generator=g)
            with torch.no_grad():
                y = block(x)
            if tuple(y.shape) != (M, c_out, H // pool, W):
                return _block_shape_failure(y, x, (M, c_out, H // pool, W), pool)
            # probe the wiring with no ReLU dead: positive weights, biases and inputs (a correct
            # block at its random initialisation can have every unit of a small layer switched off)
            _excite(block, g)
            xp = (torch.rand(M, c_in, H, W, generator=g) + 0.1).requires_grad_(True)
            block(xp).sum().backward()
            if xp.grad is None or xp.grad.abs().sum() == 0:
                return False, "the output does not depend on the input (no gradient reaches it)."
            reach = _column_reach(block, xp.detach())
            if reach != 2:
                hint = {1: " That is one 3x3 convolution's reach: the block has two, one after the other.",
                        0: " Columns do not see their neighbours: the convolutions are 3x3 with padding 1."}.get(
                    reach, " Keep the convolutions 3x3 and do not pool or mix across columns.")
                return False, (f"a change in one column reached {reach} columns to each side; two 3x3 "
                               f"convolutions in a row reach exactly 2.{hint}")
            failure = _what_is_left(block, x, c_in, pool) if c_in == c_out else None
            if failure:
                return failure
        return True, ("right shapes, rows pooled by averaging, columns kept, two 3x3 convolutions' reach, "
                      "and the skip connection carries the input.")

    # the library's own block does not count, built or subclassed
    return _run("05.1", guarded(body, ResidualBlock.__init__, ResidualBlock.forward))


# ---------------------------------------------------------------------------------------------
# 06.1: DAgger's coin

def _mix_shares(student_fn, g, u_l, u_e):
    for p in (0.0, 0.33, 1.0):
        gen = torch.Generator().manual_seed(int(torch.randint(0, 2 ** 31, (1,), generator=g)))
        got = _as_tensor(student_fn(u_l.clone(), u_e.clone(), p, gen), u_l.shape, "the applied actions")
        is_l, is_e = (got == u_l).all(dim=-1), (got == u_e).all(dim=-1)
        if not (is_l | is_e).all():
            return False, "every agent's action must be exactly the learner's or the expert's, not a blend."
        if not (is_l.all(dim=1) | is_e.all(dim=1)).all():
            return False, "draw one coin per swarm and step: a swarm follows one policy as a whole."
        share = is_l.all(dim=1).double().mean().item()
        if abs(share - p) > 0.03:
            return False, f"with p = {p} your swarms followed the learner {share:.0%} of the time."
    return None


def check_dagger_mix(student_fn: Callable) -> CheckResult:
    """Exercise 06.1: ``student_fn(u_learner, u_expert, p, generator) -> u`` applies, for each swarm
    (the first axis), the learner's actions with probability p and the expert's otherwise (DAgger's
    mixing rule, paper: p = 0.33), its coins drawn from ``generator``. u_learner, u_expert: (B, N, 2)."""
    student_fn = guarded(student_fn, dagger_mix)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        B, N = 4000, 5
        u_l = torch.randn(B, N, 2, generator=g, dtype=torch.float64)
        u_e = torch.randn(B, N, 2, generator=g, dtype=torch.float64) + 10.0
        failure = _mix_shares(student_fn, g, u_l, u_e)
        if failure:
            return failure
        # reproducible: the coins come from the generator given, not from torch's global one
        seed = int(torch.randint(0, 2 ** 31, (1,), generator=g))
        runs = []
        for stir in (1, 2):
            torch.manual_seed(seed + stir)  # the global generator in another state for each run
            runs.append(_as_tensor(student_fn(u_l.clone(), u_e.clone(), 0.5, torch.Generator().manual_seed(seed)),
                                   u_l.shape, "the applied actions"))
        if not torch.equal(runs[0], runs[1]):
            return False, ("two calls with generators seeded alike gave different coins: draw them from the "
                           "`generator` argument (e.g. torch.rand(B, generator=generator)), not from torch's "
                           "global random state, so that a training run can be reproduced.")
        return True, "one coin per swarm from the generator given, learner with probability p, expert otherwise."

    return _run("06.1", body)


# ---------------------------------------------------------------------------------------------
# 06.2: the K-step BPTT loss

def _reference_bptt(cnn, mlp, images, S, u_star):
    """The library's eq. 10 through figure 3 (``vgai_training.bptt_loss``), on this check's networks."""
    return bptt_loss(SimpleNamespace(cnn=cnn, mlp=mlp), images, S, u_star)


def check_bptt_loss(student_fn: Callable) -> CheckResult:
    """Exercise 06.2: ``student_fn(cnn, mlp, images, S, u_star) -> loss``: the loss of one step of
    K-step BPTT (the paper's figure 3) on M windows of K steps. ``images`` (M, K, N, D): every agent's
    input at the window's K steps (oldest first); ``cnn`` maps (P, D) -> (P, F); ``S`` (M, K, N, N)
    the GSOs at those steps; ``u_star`` (M, N, 2) the expert's action at each window's last step.
    Run the CNN on all K steps' inputs, build Z at the last step (eq. 6), act once with ``mlp``
    ((M, N, K, F) -> (M, N, 2)), and return the L1 loss (eq. 10, the mean over windows, agents and
    both components), differentiable down to the CNN at every step."""
    student_fn = guarded(student_fn, bptt_loss, window_action_loss)  # the library's own answer does not count
    def body():
        g = _fresh_generator()
        M, K, N, D, F = 3, int(torch.randint(3, 6, (1,), generator=g)), int(torch.randint(6, 10, (1,), generator=g)), 5, 3
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(int(torch.randint(0, 2 ** 31, (1,), generator=g)))
            cnn = nn.Sequential(nn.Linear(D, F), nn.Tanh()).double()
            mlp = nn.Sequential(nn.Flatten(-2), nn.Linear(K * F, 2)).double()
        images = torch.randn(M, K, N, D, generator=g, dtype=torch.float64)
        ring = torch.roll(torch.eye(N, dtype=torch.float64), 1, 0)
        ring = ring + ring.T  # every step's graph connected, so that every step reaches the last one
        for _ in range(50):  # graphs that change at every step, so that S(t) S(t-1) != S(t)^2
            S = torch.stack([gso(((_random_adjacency(g, K, N) + ring) > 0).double(), "sym_normalized") for _ in range(M)])
            if not (S[:, 1:] == S[:, :-1]).flatten(2).all(-1).any():
                break
        u_star = torch.randn(M, N, 2, generator=g, dtype=torch.float64)
        want = _reference_bptt(cnn, mlp, images, S, u_star)
        got = student_fn(cnn, mlp, images, S.clone(), u_star.clone())
        if not (isinstance(got, torch.Tensor) and got.numel() == 1):
            raise AnswerMismatch(f"expected the loss as a one-number tensor, got {type(got).__name__}"
                                 + (f" of shape {tuple(got.shape)}" if isinstance(got, torch.Tensor) else ""))
        if not _close(got.detach().reshape(()), want.detach()):
            ratio = (got.detach().reshape(()) / want.detach()).item()
            hint = ""
            if abs(ratio - M * N * 2) < 1e-3 * M * N * 2 or abs(ratio - 2) < 1e-3:
                hint = " Take the mean of |u - u*| over windows, agents and both components (F.l1_loss), not the sum."
            elif _close(got.detach().reshape(()), nnf.mse_loss(mlp(aggregation_sequence(
                    cnn(images.flatten(0, 2)).view(M, K, N, F), S, K)[:, -1]), u_star).detach()):
                hint = " That is the squared error; eq. 10 is the L1 loss."
            return False, f"on {M} random windows of K = {K} steps expected the loss {want.item():.6g}, got {got.item():.6g}.{hint}"
        if not got.requires_grad:
            return False, "the loss carries no gradient: do not detach it or compute it under torch.no_grad()."
        images_g = images.clone().requires_grad_(True)
        got_g = student_fn(cnn, mlp, images_g, S.clone(), u_star.clone())
        (grad,) = torch.autograd.grad(got_g.reshape(()), images_g, allow_unused=True)
        if grad is None or grad[:, 0].abs().sum() == 0:
            return False, ("no gradient reaches the CNN at the window's first step: the loss must backpropagate "
                           "through all K passes of the CNN (do not detach the earlier steps' features).")
        # the gradient at every step and agent: a loss whose value is right by chance (e.g. S(t)^k in place of
        # S(t) S(t-1) ... whose effect on one number can be tiny) still routes each step's features wrongly
        images_r = images.clone().requires_grad_(True)
        (want_grad,) = torch.autograd.grad(_reference_bptt(cnn, mlp, images_r, S, u_star), images_r)
        if not torch.allclose(grad.to(want_grad.dtype), want_grad, rtol=1e-3, atol=1e-3 * want_grad.abs().max().item()):
            return False, ("the loss's gradient with respect to the inputs is not eq. 10's: step t - k's features "
                           "reach the last step through S(t) S(t-1) ... S(t-k+1), the GSOs of the steps between "
                           "(eq. 6), not through S(t)^k.")
        return True, f"the L1 loss at the window's last step, with gradients through all K = {K} CNN passes."

    return _run("06.2", body)
