"""The exercise checks as tests of the student: every plausible wrong answer fails on every
run, every correct answer passes however it is written. Each check draws fresh random inputs, so each
case runs several times."""

from __future__ import annotations

from types import SimpleNamespace

import math

import pytest
import torch
import torch.nn.functional as nnf
from torch import nn

from vgai_lite.lab.exercises import check_aggregation_sequence
from vgai_lite.lab.method_exercises import (check_bptt_loss, check_dagger_mix, check_dagger_round, check_residual_block,
                                         check_sym_gso)
from vgai_lite.aggregation import aggregation_sequence
from vgai_lite.lab.experiment_exercises import check_circular_conv, check_variance_at

REPEATS = 5


def passes(check, answer) -> list[bool]:
    return [bool(check(answer)) for _ in range(REPEATS)]


# ---------------------------------------------------------------------------------------------
# 02.1: Z(t)

def z_loop(X, S, K, wrap=False, reverse=False, dtype=None):
    T = X.shape[0]
    t = T - 1
    blocks = []
    for k in range(K):
        if t - k < 0 and not wrap:
            blocks.append(torch.zeros_like(X[0]))
            continue
        block = X[t - k]
        order = range(t, t - k, -1) if reverse else range(t - k + 1, t + 1)
        for s in order:
            block = S[s] @ block
        blocks.append(block)
    return torch.stack(blocks, dim=1)


def z_recursive_float32(X, S, K):
    """Correct, written another way: the recursion Z_k(t) = S(t) Z_{k-1}(t-1), in float32."""
    X, S = X.float(), S.float()
    T, N, F = X.shape

    def Zk(k, t):
        if t < 0:
            return torch.zeros(N, F)
        return X[t] if k == 0 else S[t] @ Zk(k - 1, t - 1)

    return torch.stack([Zk(k, T - 1) for k in range(K)], dim=1)


def z_padded(X, S, K):
    """Correct: pad the history with K zeros, then the product from the left."""
    T, N, F = X.shape
    Xp = torch.cat((torch.zeros(K, N, F, dtype=X.dtype), X))
    Sp = torch.cat((torch.zeros(K, N, N, dtype=S.dtype), S))
    t = T - 1 + K
    out = []
    for k in range(K):
        z = Xp[t - k]
        for s in range(t - k + 1, t + 1):
            z = Sp[s] @ z
        out.append(z)
    return torch.stack(out, 1)


@pytest.mark.parametrize("answer", [z_loop, z_recursive_float32, z_padded], ids=["loop", "recursion-float32", "padded"])
def test_02_1_passes_correct_answers(answer):
    assert all(passes(check_aggregation_sequence, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda X, S, K: z_loop(X, S, K, wrap=True), "negative index wraps"),
    (lambda X, S, K: z_loop(X, S, K, reverse=True), "product in reverse order"),
    (lambda X, S, K: torch.stack([torch.linalg.matrix_power(S[-1], k) @ X[-1 - k] if k < X.shape[0]
                                  else torch.zeros_like(X[0]) for k in range(K)], 1), "S(t)^k"),
    (lambda X, S, K: torch.stack([torch.linalg.matrix_power(S[-1], k) @ X[-1] for k in range(K)], 1), "no delay"),
])
def test_02_1_rejects_wrong_answers(answer, why):
    assert not any(passes(check_aggregation_sequence, answer)), why


def test_02_1_names_the_wrap_around():
    msg = check_aggregation_sequence(lambda X, S, K: z_loop(X, S, K, wrap=True)).message
    assert "wraps around" in msg


# ---------------------------------------------------------------------------------------------
# 05.1: the residual block

class Block(nn.Module):
    def __init__(self, c_in, c_out, pool, skip=True, pooling="avg", convs=2, relu_after_pool=False,
                 always_1x1=False):
        super().__init__()
        self.conv1 = nn.Conv2d(c_in, c_out, 3, padding=1)
        self.conv2 = nn.Conv2d(c_out, c_out, 3, padding=1) if convs == 2 else None
        self.skip = nn.Conv2d(c_in, c_out, 1) if (c_in != c_out or always_1x1) else nn.Identity()
        self.use_skip, self.pooling, self.pool_rows, self.relu_after_pool = skip, pooling, pool, relu_after_pool

    def forward(self, x):
        y = self.conv1(x)
        if self.conv2 is not None:
            y = self.conv2(torch.relu(y))
        if self.use_skip:
            y = y + self.skip(x)
        if not self.relu_after_pool:
            y = torch.relu(y)
        pool = nnf.avg_pool2d if self.pooling == "avg" else nnf.max_pool2d
        y = pool(y, (self.pool_rows, 1))
        return torch.relu(y) if self.relu_after_pool else y


class SequentialBlock(nn.Module):
    """Correct, another layout: the branch as an nn.Sequential, pooling by reshaping and averaging."""

    def __init__(self, c_in, c_out, pool):
        super().__init__()
        self.branch = nn.Sequential(nn.Conv2d(c_in, c_out, kernel_size=(3, 3), padding=(1, 1)), nn.ReLU(),
                                    nn.Conv2d(c_out, c_out, kernel_size=3, padding="same"))
        self.shortcut = nn.Conv2d(c_in, c_out, kernel_size=1, bias=False) if c_in != c_out else None
        self.pool = pool

    def forward(self, x):
        s = x if self.shortcut is None else self.shortcut(x)
        y = nnf.relu(self.branch(x) + s)
        M, C, H, W = y.shape
        return y.view(M, C, H // self.pool, self.pool, W).mean(3)


@pytest.mark.parametrize("answer", [
    lambda ci, co, p: Block(ci, co, p),
    lambda ci, co, p: Block(ci, co, p, always_1x1=True),
    SequentialBlock,
], ids=["library-like", "1x1-skip-always", "sequential-reshape"])
def test_05_1_passes_correct_answers(answer):
    assert all(passes(check_residual_block, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda ci, co, p: Block(ci, co, p, skip=False), "no skip connection"),
    (lambda ci, co, p: Block(ci, co, p, pooling="max"), "max pooling"),
    (lambda ci, co, p: Block(ci, co, p, convs=1), "one convolution"),
    (lambda ci, co, p: Block(ci, co, p, relu_after_pool=True), "ReLU after the pooling"),
])
def test_05_1_rejects_wrong_answers(answer, why):
    assert not any(passes(check_residual_block, answer)), why


# ---------------------------------------------------------------------------------------------
# 06.1: DAgger's coin

def mix_library(u_l, u_e, p, generator):
    follow = torch.rand(u_e.shape[0], generator=generator) < p
    return torch.where(follow[:, None, None], u_l, u_e)


def mix_bernoulli_loop(u_l, u_e, p, generator):
    """Correct, another way: a Bernoulli draw per swarm, a loop."""
    coins = torch.bernoulli(torch.full((u_e.shape[0],), float(p)), generator=generator)
    out = u_e.clone()
    for b in range(u_e.shape[0]):
        if coins[b] == 1:
            out[b] = u_l[b]
    return out


@pytest.mark.parametrize("answer", [mix_library, mix_bernoulli_loop])
def test_06_1_passes_correct_answers(answer):
    assert all(passes(check_dagger_mix, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda u_l, u_e, p, generator: mix_library(u_l, u_e, p, None), "global generator"),
    (lambda u_l, u_e, p, generator: torch.where((torch.rand(u_e.shape[:2], generator=generator) < p)[..., None],
                                                u_l, u_e), "one coin per agent"),
    (lambda u_l, u_e, p, generator: p * u_l + (1 - p) * u_e, "a blend"),
    (lambda u_l, u_e, p, generator: mix_library(u_l, u_e, 1 - p, generator), "p for the expert"),
])
def test_06_1_rejects_wrong_answers(answer, why):
    assert not any(passes(check_dagger_mix, answer)), why


# ---------------------------------------------------------------------------------------------
# 05.2: the convolution that wraps around

class Circular(nn.Module):
    def __init__(self, c_in, c_out, kernel=(1, 3), rows_too=False, pad_mode="circular"):
        super().__init__()
        self.conv = nn.Conv2d(c_in, c_out, kernel)
        self.rows_too, self.pad_mode = rows_too, pad_mode

    def forward(self, x):
        pad = (1, 1, 1, 1) if self.rows_too else (1, 1, 0, 0)
        return self.conv(nnf.pad(x, pad, mode=self.pad_mode))


class CircularByCat(nn.Module):
    """Correct, another way: concatenate the last and first columns, then a 1x3 convolution."""

    def __init__(self, c_in, c_out):
        super().__init__()
        self.conv = nn.Conv2d(c_in, c_out, (1, 3))

    def forward(self, x):
        return self.conv(torch.cat((x[..., -1:], x, x[..., :1]), dim=-1))


@pytest.mark.parametrize("answer", [lambda ci, co: Circular(ci, co), CircularByCat,
                                    lambda ci, co: nn.Conv2d(ci, co, (1, 3), padding=(0, 1), padding_mode="circular")],
                         ids=["pad-circular", "cat", "padding_mode"])
def test_05_2_passes_correct_answers(answer):
    assert all(passes(check_circular_conv, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda ci, co: Circular(ci, co, kernel=(3, 3), rows_too=True), "3x3 circular in both directions"),
    (lambda ci, co: Circular(ci, co, pad_mode="constant"), "zero padding"),
    (lambda ci, co: Circular(ci, co, pad_mode="replicate"), "replicate padding"),
])
def test_05_2_rejects_wrong_answers(answer, why):
    assert not any(passes(check_circular_conv, answer)), why


# ---------------------------------------------------------------------------------------------
# 07.1: the variance at a time

def variance_at(v, Ts, seconds, index=round, ddof=0, center=True):
    step = index(seconds / Ts)
    w = v[step]
    if center:
        w = w - w.mean(1, keepdim=True)
    N = v.shape[2]
    return w.square().sum(-1).sum(-1) / (N - ddof)


@pytest.mark.parametrize("answer", [
    variance_at,
    lambda v, Ts, s: v[int(s / Ts + 0.5)].float().var(dim=1, unbiased=False).sum(-1),
], ids=["round", "int+0.5-float32-var"])
def test_07_1_passes_correct_answers(answer):
    assert all(passes(check_variance_at, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda v, Ts, s: variance_at(v, Ts, s, index=int), "int truncates"),
    (lambda v, Ts, s: variance_at(v, Ts, s, index=math.floor), "floor"),
    (lambda v, Ts, s: variance_at(v, Ts, s, index=math.ceil), "ceil"),
    (lambda v, Ts, s: variance_at(v, Ts, s, ddof=1), "N - 1"),
    (lambda v, Ts, s: variance_at(v, Ts, s, center=False), "not centred"),
])
def test_07_1_rejects_wrong_answers(answer, why):
    assert not any(passes(check_variance_at, answer)), why


def test_07_1_says_why_truncation_fails():
    msg = check_variance_at(lambda v, Ts, s: variance_at(v, Ts, s, index=int)).message
    assert "round(seconds / Ts)" in msg


def test_a_checks_own_shape_test_is_not_reported_as_the_students_error():
    msg = check_variance_at(lambda v, Ts, s: variance_at(v, Ts, s)[None]).message
    assert "expected one variance per flight of shape" in msg and "raised" not in msg


# ---------------------------------------------------------------------------------------------
# 02.2: the symmetric normalised GSO

def sym_where(A):
    d = A.sum(-1)
    inv = torch.where(d > 0, d.rsqrt(), torch.zeros_like(d))
    return inv[..., :, None] * A * inv[..., None, :]


def sym_diag_loop_float32(A):
    """Correct, another way: D^-1/2 as a matrix, per graph, in float32, isolated drones by nan_to_num."""
    out = []
    for a in A.float():
        D = torch.diag(a.sum(-1).pow(-0.5))
        out.append(torch.nan_to_num(D @ a @ D, posinf=0.0))
    return torch.stack(out)


@pytest.mark.parametrize("answer", [sym_where, sym_diag_loop_float32])
def test_02_2_passes_correct_answers(answer):
    assert all(passes(check_sym_gso, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda A: A.sum(-1).rsqrt()[..., :, None] * A * A.sum(-1).rsqrt()[..., None, :], "isolated drone gives NaN"),
    (lambda A: A / A.sum(-1).clamp(min=1)[..., None], "row-normalised"),
    (lambda A: sym_where(A + torch.eye(A.shape[-1], dtype=A.dtype)), "self-loops"),
    (lambda A: A * A.sum(-1).clamp(min=1).rsqrt()[..., None, :], "one side only"),
    (lambda A: A, "not normalised"),
])
def test_02_2_rejects_wrong_answers(answer, why):
    assert not any(passes(check_sym_gso, answer)), why


def test_02_2_draws_no_graph_on_which_a_one_sided_normalisation_is_right():
    """On a graph whose every edge joins two drones of equal degree (a few disjoint pairs, say, which sparse draws of
    six drones often are), D^-1 A equals D^-1/2 A D^-1/2: the row-normalised answer would pass now and then."""
    from vgai_lite.graphs import gso
    from vgai_lite.lab.method_exercises import _random_adjacency

    for seed in range(300):
        A = _random_adjacency(torch.Generator().manual_seed(seed), 1, 6)  # graph by graph, as a check of one graph would meet it
        row = A / A.sum(-1).clamp(min=1)[..., None]
        assert not torch.allclose(row, gso(A, "sym_normalized")), seed
        assert (A.diagonal(dim1=-2, dim2=-1) == 0).all() and torch.equal(A, A.transpose(1, 2))
        assert (A.sum(-1) == 0).any(-1).all()  # each graph keeps its isolated drone


# ---------------------------------------------------------------------------------------------
# 03.2: one DAgger round's data aggregation

def round_right(data, learner, expert, mix, step, r, v, steps, label="expert", fly="mix", keep=True, late=False):
    new = {"r": [], "v": [], "u": []}
    for _ in range(steps):
        u_star = expert(r, v)
        u = {"mix": lambda: mix(learner(r, v), u_star), "expert": lambda: u_star}[fly]()
        if not late:
            new["r"].append(r), new["v"].append(v)
        new["u"].append({"expert": u_star, "applied": u, "learner": learner(r, v)}[label])
        r, v = step(r, v, u)
        if late:
            new["r"].append(r), new["v"].append(v)
    return {k: (data[k] if keep else []) + new[k] for k in new}


def round_extend_in_place(data, learner, expert, mix, step, r, v, steps):
    """Correct, another way: extend the lists in place, labels computed after the coin."""
    for _ in range(steps):
        u = mix(learner(r, v), expert(r, v))
        data["r"].append(r.clone()), data["v"].append(v.clone()), data["u"].append(expert(r, v))
        r, v = step(r, v, u)
    return data


@pytest.mark.parametrize("answer", [round_right, round_extend_in_place])
def test_03_2_passes_correct_answers(answer):
    assert all(passes(check_dagger_round, answer))


@pytest.mark.parametrize("kwargs,why", [
    (dict(label="applied"), "labels are the applied actions"),
    (dict(label="learner"), "labels are the learner's"),
    (dict(fly="expert"), "the learner never flies"),
    (dict(keep=False), "earlier rounds dropped"),
    (dict(late=True), "state after the step recorded"),
])
def test_03_2_rejects_wrong_answers(kwargs, why):
    assert not any(passes(check_dagger_round, lambda *a: round_right(*a, **kwargs))), why


# ---------------------------------------------------------------------------------------------
# 06.2: the K-step BPTT loss

def bptt_right(cnn, mlp, images, S, u_star, detach_past=False, loss="l1", reduce="mean", power=False):
    M, K, N, D = images.shape
    X = cnn(images.reshape(-1, D)).view(M, K, N, -1)
    if detach_past:
        X = torch.cat((X[:, :-1].detach(), X[:, -1:]), 1)
    if power:
        blocks = [torch.linalg.matrix_power(S[:, -1], k) @ X[:, -1 - k] for k in range(K)]
        Z = torch.stack(blocks, 2)
    else:
        Z = aggregation_sequence(X, S, K)[:, -1]
    u = mlp(Z)
    if loss == "mse":
        return nnf.mse_loss(u, u_star)
    return (u - u_star).abs().mean() if reduce == "mean" else (u - u_star).abs().sum()


def bptt_loop_float32(cnn, mlp, images, S, u_star):
    """Correct, another way: the delayed aggregation by a loop over agents' messages, in float32."""
    cnn32, mlp32 = cnn.float(), mlp.float()
    try:
        M, K, N, D = images.shape
        X = cnn32(images.float())  # (M, K, N, F)
        t = K - 1
        blocks = []
        for k in range(K):
            z = X[:, t - k]
            for s in range(t - k + 1, t + 1):
                z = S[:, s].float() @ z
            blocks.append(z)
        return (mlp32(torch.stack(blocks, 2)) - u_star.float()).abs().mean()
    finally:
        cnn.double(), mlp.double()


@pytest.mark.parametrize("answer", [bptt_right, bptt_loop_float32])
def test_06_2_passes_correct_answers(answer):
    assert all(passes(check_bptt_loss, answer))


@pytest.mark.parametrize("kwargs,why", [
    (dict(detach_past=True), "earlier steps detached: no BPTT"),
    (dict(loss="mse"), "squared error"),
    (dict(reduce="sum"), "sum instead of mean"),
    (dict(power=True), "S(t)^k"),
])
def test_06_2_rejects_wrong_answers(kwargs, why):
    assert not any(passes(check_bptt_loss, lambda *a: bptt_right(*a, **kwargs))), why


def test_06_2_rejects_a_loss_without_gradient():
    assert not any(passes(check_bptt_loss, lambda *a: bptt_right(*a).detach()))


# ---------------------------------------------------------------------------------------------
# 01.1: the potential's gradient (eq. 3)

from vgai_lite.lab.exercises import check_flocking_cost, check_local_features, check_pinhole, check_potential_gradient  # noqa: E402
from vgai_lite.lab.experiment_exercises import check_odd_part  # noqa: E402


def grad_u(r_ij, rho, dtype=None, cut="norm", sign=+1.0, factor=2.0, first_power=2, log_power=2):
    r = r_ij if dtype is None else r_ij.to(dtype)
    d = r.norm(dim=-1, keepdim=True)
    # U = 1/d^p - log d^q: grad = -p r / d^(p+2) - sign q r / d^2
    g = -first_power * r / d ** (first_power + 2) - sign * log_power * r / d ** 2
    g = g * factor / 2
    inside = {"norm": d <= rho, "square": d ** 2 <= rho, "none": torch.ones_like(d, dtype=torch.bool)}[cut]
    return torch.where(inside, g, torch.zeros_like(g))


def grad_u_loop(r_ij, rho):
    """Correct, another way: one offset at a time with Python floats."""
    out = torch.zeros_like(r_ij)
    for k, (x, y) in enumerate(r_ij.tolist()):
        d2 = x * x + y * y
        if math.sqrt(d2) <= rho:
            w = -2 / d2 ** 2 - 2 / d2
            out[k] = torch.tensor([w * x, w * y])
    return out


@pytest.mark.parametrize("answer", [grad_u, lambda r, rho: grad_u(r, rho, dtype=torch.float32), grad_u_loop],
                         ids=["vector", "float32", "loop"])
def test_01_1_passes_correct_answers(answer):
    assert all(passes(check_potential_gradient, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda r, rho: grad_u(r, rho, cut="none"), "no cut-off at rho"),
    (lambda r, rho: grad_u(r, rho, cut="square"), "||r||^2 <= rho instead of ||r|| <= rho"),
    (lambda r, rho: -grad_u(r, rho), "gradient with respect to r_j"),
    (lambda r, rho: grad_u(r, rho, factor=1.0), "d/dr ||r||^2 = r"),
    (lambda r, rho: grad_u(r, rho, sign=-1.0), "+log instead of -log (the reference code's potential)"),
    (lambda r, rho: grad_u(r, rho, log_power=1), "log ||r|| instead of log ||r||^2"),
    (lambda r, rho: grad_u(r, rho, first_power=1), "1/||r|| instead of 1/||r||^2"),
])
def test_01_1_rejects_wrong_answers(answer, why):
    assert not any(passes(check_potential_gradient, answer)), why


# ---------------------------------------------------------------------------------------------
# 01.2: the flocking cost (eq. 1)

def cost_loop(v):
    """Correct, another way: loops over time and swarms, in float32."""
    v = v.float()
    T, B, N, _ = v.shape
    out = torch.zeros(B)
    for b in range(B):
        for t in range(T):
            mean = v[t, b].mean(0)
            out[b] += ((v[t, b] - mean) ** 2).sum() / N
    return out


def cost_var(v):
    """Correct: the biased variance of each component, summed."""
    return v.var(dim=2, unbiased=False).sum(-1).sum(0)


@pytest.mark.parametrize("answer", [cost_loop, cost_var])
def test_01_2_passes_correct_answers(answer):
    assert all(passes(check_flocking_cost, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda v: v.var(dim=2).sum(-1).sum(0), "unbiased variance (N - 1)"),
    (lambda v: v.var(dim=2, unbiased=False).sum(-1).mean(0), "mean over time"),
    (lambda v: v.norm(dim=-1).var(dim=2, unbiased=False).sum(0), "variance of the speeds"),
    (lambda v: ((v - v.mean(dim=(0, 2), keepdim=True)) ** 2).sum(-1).mean(2).sum(0), "mean over all times"),
    (lambda v: (v - v.mean(2, keepdim=True)).norm(dim=-1).mean(2).sum(0), "norm not squared"),
    (lambda v: ((v - v.mean(2, keepdim=True)) ** 2).sum(-1).sum(2).sum(0), "no 1/N"),
])
def test_01_2_rejects_wrong_answers(answer, why):
    assert not any(passes(check_flocking_cost, answer)), why


# ---------------------------------------------------------------------------------------------
# 03.1: the six local features

def features(r, v, R, cut="norm", power4=4, sign=1.0, self_in=False, vsign=1.0, dtype=None):
    if dtype is not None:
        r, v = r.to(dtype), v.to(dtype)
    rij = r[:, None] - r[None]                       # r_i - r_j
    d = rij.norm(dim=-1)
    A = {"norm": d <= R, "square": d ** 2 <= R, "none": torch.ones_like(d, dtype=torch.bool)}[cut]
    if not self_in:
        A = A & ~torch.eye(len(r), dtype=torch.bool)
    A = A.to(r.dtype)
    dv = vsign * (A[..., None] * (v[:, None] - v[None])).sum(1)
    d_ = (d + torch.diag(torch.full((len(r),), 0.0 if self_in else math.inf, dtype=d.dtype)))[..., None]
    rep4 = sign * (A[..., None] * rij / d_ ** power4).sum(1)
    rep2 = sign * (A[..., None] * rij / d_ ** 2).sum(1)
    return torch.cat((dv, rep4, rep2), -1)


def features_loop(r, v, R):
    """Correct, another way: loops over agents and neighbours, in float32."""
    r, v = r.float(), v.float()
    N = len(r)
    X = torch.zeros(N, 6)
    for i in range(N):
        for j in range(N):
            rij = r[i] - r[j]
            d = rij.norm()
            if i != j and d <= R:
                X[i, 0:2] += v[i] - v[j]
                X[i, 2:4] += rij / d ** 4
                X[i, 4:6] += rij / d ** 2
    return X


@pytest.mark.parametrize("answer", [features, features_loop])
def test_03_1_passes_correct_answers(answer):
    assert all(passes(check_local_features, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda r, v, R: features(r, v, R, cut="none"), "every agent a neighbour"),
    (lambda r, v, R: features(r, v, R, cut="square"), "||r||^2 <= R"),
    (lambda r, v, R: features(r, v, R, power4=3), "r/||r||^3"),
    (lambda r, v, R: features(r, v, R, sign=-1.0), "r_j - r_i"),
    (lambda r, v, R: features(r, v, R, vsign=-1.0), "v_j - v_i"),
    (lambda r, v, R: features(r, v, R, self_in=True), "agent i its own neighbour"),
])
def test_03_1_rejects_wrong_answers(answer, why):
    assert not any(passes(check_local_features, answer)), why


# ---------------------------------------------------------------------------------------------
# 04.1: the pinhole camera

def pinhole(theta, d, rcfg, mirror=False, ccw=False, near_side=True, focal=None):
    psi = ((theta - math.pi / 4) if ccw else (math.pi / 4 - theta)) % (2 * math.pi)
    cam = min(math.floor(psi / (math.pi / 2)), 3)
    phi = psi - cam * math.pi / 2 - math.pi / 4
    W = rcfg.view_width
    u = cam * W + W / 2 + (-1 if mirror else 1) * rcfg.focal * math.tan(phi)
    f = rcfg.focal_vertical if focal is None else focal(rcfg)
    h = 2 * f * (rcfg.body_height / 2) / (d - rcfg.body_radius if near_side else d)
    return u, h


def pinhole_atan2(theta, d, rcfg):
    """Correct, another way: the bearing relative to each camera's axis with atan2, float32 tensors."""
    axes = [-k * math.pi / 2 for k in range(4)]  # front (+x), right, back, left: clockwise
    for cam, axis in enumerate(axes):
        phi = -math.atan2(math.sin(theta - axis), math.cos(theta - axis))  # to the right of the axis
        if -math.pi / 4 <= phi < math.pi / 4:
            break
    W = rcfg.view_width
    u = torch.tensor(cam * W + W / 2 + rcfg.focal * math.tan(phi), dtype=torch.float64)
    fv = (rcfg.view_height / 2) / math.tan(math.radians(rcfg.vertical_fov_deg) / 2)
    return u, torch.tensor(fv * rcfg.body_height / (d - rcfg.body_radius))


@pytest.mark.parametrize("answer", [pinhole, pinhole_atan2])
def test_04_1_passes_correct_answers(answer):
    assert all(passes(check_pinhole, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda t, d, c: pinhole(t, d, c, mirror=True), "columns run right to left"),
    (lambda t, d, c: pinhole(t, d, c, ccw=True), "cameras counter-clockwise"),
    (lambda t, d, c: pinhole(t, d, c, near_side=False), "centre distance, not the near side"),
    (lambda t, d, c: pinhole(t, d, c, focal=lambda rc: rc.focal), "the horizontal focal length"),
])
def test_04_1_rejects_wrong_answers(answer, why):
    assert not any(passes(check_pinhole, answer)), why


# ---------------------------------------------------------------------------------------------
# 06.3: the odd part

def odd_sign_vector(f, images):
    """Correct, another way: mirror with a per-channel sign."""
    c = images.shape[1] // 2
    sign = torch.cat((torch.ones(c), -torch.ones(c))).view(1, -1, 1, 1)
    return 0.5 * (f(images) - f(images * sign))


def odd_part(f, images, half="second"):
    c = images.shape[1] // 2
    m = images.clone()
    if half == "second":
        m[:, c:] = -m[:, c:]
    elif half == "first":
        m[:, :c] = -m[:, :c]
    else:
        m = -m
    return (f(images) - f(m)) / 2


@pytest.mark.parametrize("answer", [odd_part, odd_sign_vector])
def test_06_3_passes_correct_answers(answer):
    assert all(passes(check_odd_part, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda f, im: odd_part(f, im, half="first"), "negates the image, not the motion"),
    (lambda f, im: odd_part(f, im, half="all"), "negates every channel"),
    (lambda f, im: -odd_part(f, im), "sign flipped"),
    (lambda f, im: f(im) - f(torch.cat((im[:, :im.shape[1] // 2], -im[:, im.shape[1] // 2:]), 1)), "no 1/2"),
    (lambda f, im: (f(im) + f(torch.cat((im[:, :im.shape[1] // 2], -im[:, im.shape[1] // 2:]), 1))) / 2, "even part"),
])
def test_06_3_rejects_wrong_answers(answer, why):
    assert not any(passes(check_odd_part, answer)), why


# ---------------------------------------------------------------------------------------------
# Every check: the library's own implementation of what the exercise asks for does not count,
# however it is reached; other library functions stay allowed.

def _library_answers():
    from types import SimpleNamespace

    import vgai_lite
    import vgai_lite as vl
    import vgai_lite.graphs
    from vgai_lite import FlockConfig
    from vgai_lite.controllers import potential_gradient
    from vgai_lite.features import local_features
    from vgai_lite.flocking import flocking_cost, velocity_variance
    from vgai_lite.graphs import gso as my_gso  # an alias
    from vgai_lite.imitation import dagger_mix
    from vgai_lite.lab.exercises import (check_flocking_cost, check_local_features, check_pinhole,
                                         check_potential_gradient)
    from vgai_lite.models import ResidualBlock
    from vgai_lite.render import bearing_to_column
    from vgai_lite.vgai_training import bptt_loss

    class Block(ResidualBlock):  # the library's block, subclassed
        def __init__(self, c_in, c_out, pool):
            super().__init__(c_in, c_out, (3, 3), pool=pool)

    return [
        ("01.1", check_potential_gradient, lambda r, rho: potential_gradient(r, FlockConfig(rho=rho))),
        ("01.2", check_flocking_cost, lambda v: flocking_cost(v)),
        ("01.2", check_flocking_cost, lambda v: velocity_variance(v).sum(0)),
        ("02.1", check_aggregation_sequence, lambda X, S, K: vl.aggregation_sequence(X[None], S[None], K)[0, -1]),
        ("02.2", check_sym_gso, lambda A: my_gso(A, "sym_normalized")),
        ("02.2", check_sym_gso, lambda A: vl.gso(A, "sym_normalized")),
        ("02.2", check_sym_gso, lambda A: vgai_lite.graphs.gso(A, "sym_normalized")),
        ("03.1", check_local_features, lambda r, v, R: local_features(r[None], v[None], R)[0]),
        ("04.1", check_pinhole, lambda theta, d, rcfg: (bearing_to_column(theta, rcfg), rcfg.view_height / d)),
        ("05.1", check_residual_block, Block),
        ("06.1", check_dagger_mix, lambda u_l, u_e, p, g: dagger_mix(u_l, u_e, p, g)),
        ("06.2", check_bptt_loss, lambda cnn, mlp, images, S, u: bptt_loss(SimpleNamespace(cnn=cnn, mlp=mlp), images, S, u)),
        ("07.1", check_variance_at, lambda v, Ts, seconds: velocity_variance(v)[round(seconds / Ts)]),
    ]


@pytest.mark.parametrize("case", range(13))
def test_an_answer_that_calls_the_librarys_own_implementation_is_told_so(case):
    exercise, check, answer = _library_answers()[case]
    result = check(answer)
    assert not result and "library's own" in result.message, (exercise, result.message)


def test_the_library_works_again_after_a_check_and_other_library_functions_stay_allowed():
    from vgai_lite.aggregation import aggregation_sequence as lib_z
    from vgai_lite.graphs import gso

    check_sym_gso(lambda A: gso(A, "sym_normalized"))  # forbidden during the answer only
    A = torch.ones(1, 3, 3) - torch.eye(3)
    torch.testing.assert_close(gso(A, "sym_normalized"), A / 2)
    # 06.2 may build Z with the library's aggregation_sequence: that is not what it asks for
    def bptt_with_library_z(cnn, mlp, images, S, u_star):
        M, K, N = images.shape[:3]
        X = cnn(images.flatten(0, 2)).view(M, K, N, -1)
        return nnf.l1_loss(mlp(lib_z(X, S, K)[:, -1]), u_star)

    assert all(passes(check_bptt_loss, bptt_with_library_z))


# ---------------------------------------------------------------------------------------------
# 05.3: the state-estimation loss

def est_right(X, head, x, mean, std):
    return nnf.l1_loss(head(X), (x - mean) / std)


def est_loop_float32(X, head, x, mean, std):
    """Correct, written another way: per feature, in float32."""
    pred = head(X).float()
    target = ((x - mean) / std).float()
    return torch.stack([(pred[:, k] - target[:, k]).abs().mean() for k in range(6)]).mean()


@pytest.mark.parametrize("answer", [est_right, est_loop_float32])
def test_05_3_passes_correct_answers(answer):
    from vgai_lite.lab.training_exercises import check_estimation_loss

    assert all(passes(check_estimation_loss, answer))


@pytest.mark.parametrize("answer,why", [
    (lambda X, h, x, m, s: nnf.l1_loss(h(X), x), "raw features"),
    (lambda X, h, x, m, s: nnf.l1_loss(h(X) * s + m, x), "un-standardised prediction"),
    (lambda X, h, x, m, s: nnf.mse_loss(h(X), (x - m) / s), "squared error"),
    (lambda X, h, x, m, s: (h(X) - (x - m) / s).abs().sum(), "sum"),
    (lambda X, h, x, m, s: nnf.l1_loss(h(X.detach()), (x - m) / s), "detached features"),
    (lambda X, h, x, m, s: nnf.l1_loss(h(X), (x - m) / s.mean()), "one spread for all"),
])
def test_05_3_rejects_wrong_answers(answer, why):
    from vgai_lite.lab.training_exercises import check_estimation_loss

    assert not any(passes(check_estimation_loss, answer)), why


def test_05_3_rejects_the_librarys_loss():
    from vgai_lite.lab.training_exercises import check_estimation_loss
    from vgai_lite.vgai_training import estimation_loss

    def via_library(X, head, x, mean, std):
        cnn = SimpleNamespace(aux_standardized=head, aux_mean=mean, aux_std=std, F=X.shape[-1])
        return estimation_loss(cnn, X, x)

    result = check_estimation_loss(via_library)
    assert not result and "library's own" in result.message


# ---------------------------------------------------------------------------------------------
# 08.1: lost messages

def lose_right(A, p, generator):
    return A * (torch.rand(A.shape, generator=generator) >= p).to(A.dtype)


def lose_bernoulli(A, p, generator):
    """Correct, written another way: keep each message with a Bernoulli draw of 1 - p."""
    return A * torch.bernoulli(torch.full(A.shape, 1.0 - p, dtype=torch.float64), generator=generator).to(A.dtype)


@pytest.mark.parametrize("answer", [lose_right, lose_bernoulli])
def test_08_1_passes_correct_answers(answer):
    from vgai_lite.lab.training_exercises import check_lost_messages

    assert all(passes(check_lost_messages, answer))


def _lose_pairs(A, p, generator):
    coin = (torch.rand(A.shape, generator=generator) >= p).float().triu(1)
    return A * (coin + coin.transpose(-1, -2))


def _lose_in_place(A, p, generator):
    A[torch.rand(A.shape, generator=generator) < p] = 0
    return A


@pytest.mark.parametrize("answer,why", [
    (lambda A, p, g: A * (torch.rand(A.shape) >= p).to(A.dtype), "global generator"),
    (lambda A, p, g: A * (torch.rand(A.shape, generator=g) >= 1 - p).to(A.dtype), "p kept, not lost"),
    (_lose_pairs, "one coin per pair"),
    (_lose_in_place, "in place"),
    (lambda A, p, g: A * (torch.rand(A.shape[:2], generator=g) >= p).to(A.dtype)[..., None], "one coin per agent"),
    (lambda A, p, g: A * (1 - p), "expected value, not a draw"),
])
def test_08_1_rejects_wrong_answers(answer, why):
    from vgai_lite.lab.training_exercises import check_lost_messages

    assert not any(passes(check_lost_messages, answer)), why


# ---------------------------------------------------------------------------------------------
# 03.3: DAgger's training loop

def dagger_loop(learner, fit, expert, step, starts, steps, p, generator, *, aggregate=True, fit_each=True,
                p0=0.0, coin="swarm", label="expert", rng="given", flip=False):
    data = {"r": [], "v": [], "u": []}
    for k, (r, v) in enumerate(starts):
        pk = p0 if k == 0 else (1 - p if flip else p)
        if not aggregate:
            data = {"r": [], "v": [], "u": []}
        for _ in range(steps):
            u_star, u_l = expert(r, v), learner(r, v)
            gen = generator if rng == "given" else None
            shape = (r.shape[0],) if coin == "swarm" else r.shape[:2]
            follow = torch.rand(shape, generator=gen) < pk
            u = torch.where(follow.view(*shape, *([1] * (3 - len(shape)))), u_l, u_star)
            data["r"].append(r), data["v"].append(v), data["u"].append(u_star if label == "expert" else u)
            r, v = step(r, v, u)
        if fit_each:
            fit(data)
    if not fit_each:
        fit(data)
    return data


def dagger_loop_with_library_coin(learner, fit, expert, step, starts, steps, p, generator):
    """Correct: the library's coin (dagger_mix) is allowed here; the loop is the exercise."""
    from vgai_lite.imitation import dagger_mix

    data = {"r": [], "v": [], "u": []}
    for k, (r, v) in enumerate(starts):
        for _ in range(steps):
            u_star = expert(r, v)
            data["r"] += [r]
            data["v"] += [v]
            data["u"] += [u_star]
            r, v = step(r, v, dagger_mix(learner(r, v), u_star, p if k else 0.0, generator))
        fit(data)
    return data


@pytest.mark.parametrize("answer", [dagger_loop, dagger_loop_with_library_coin])
def test_03_3_passes_correct_answers(answer):
    from vgai_lite.lab.training_exercises import check_dagger_training

    assert all(passes(check_dagger_training, answer))


@pytest.mark.parametrize("kwargs,why", [
    ({"aggregate": False}, "each round's data alone"),
    ({"fit_each": False}, "one fit at the end"),
    ({"p0": 0.4}, "the untrained learner flies round 0"),
    ({"coin": "agent"}, "one coin per agent"),
    ({"rng": "global"}, "global generator"),
    ({"label": "applied"}, "labels are the applied actions"),
    ({"flip": True}, "p for the expert"),
])
def test_03_3_rejects_wrong_answers(kwargs, why):
    from vgai_lite.lab.training_exercises import check_dagger_training

    answer = lambda *args: dagger_loop(*args, **kwargs)
    assert not any(passes(check_dagger_training, answer)), why


def test_03_3_rejects_a_loop_that_never_fits_and_the_librarys_training():
    from vgai_lite.dagnn_training import train_dagnn
    from vgai_lite.lab.training_exercises import check_dagger_training

    never = lambda learner, fit, expert, step, starts, steps, p, g: {"r": [], "v": [], "u": []}
    assert not check_dagger_training(never)

    def library(learner, fit, expert, step, starts, steps, p, g):
        train_dagnn(vl_cfg_small())
        return {"r": [], "v": [], "u": []}

    result = check_dagger_training(library)
    assert not result and "library's own" in result.message


def vl_cfg_small():
    from vgai_lite import FlockConfig

    return FlockConfig(N=5, T=5)
