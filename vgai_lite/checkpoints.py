"""Saving and loading learned controllers: one file holds the config, the architecture and the weights.

Introduced in notebook 03. Files are written with ``torch.save`` and read with
``torch.load(..., weights_only=True)``: only tensors and plain values, so loading never runs code.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Optional, Union

import torch

from .config import FlockConfig

FORMAT = "vgai-lite-controller/1"


def save_controller(path: Union[str, Path], controller, meta: Optional[dict] = None) -> Path:
    """Write ``controller`` (it must have ``spec()``, ``model`` and ``cfg``) and ``meta`` to ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = {
        "format": FORMAT,
        "spec": controller.spec(),
        "config": dataclasses.asdict(controller.cfg),
        "state_dict": {k: v.detach().cpu() for k, v in controller.model.state_dict().items()},
        "meta": meta or {},
    }
    tmp = path.with_suffix(path.suffix + ".tmp")
    torch.save(payload, tmp)
    tmp.replace(path)  # never leave a half-written checkpoint behind
    return path


def read_checkpoint(path: Union[str, Path]) -> dict:
    """The raw payload of a checkpoint file, with clear errors for missing or corrupt files."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no checkpoint at {path}: train one first (see notebook 03, "
                                f"vgai_lite.imitation.load_or_train) or check the path")
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:
        raise ValueError(f"{path} is not a readable vgai-lite checkpoint ({type(exc).__name__}: {exc}); "
                         f"delete it and train again") from exc
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        got = payload.get("format") if isinstance(payload, dict) else type(payload).__name__
        raise ValueError(f"{path} is not a vgai-lite controller checkpoint (expected format {FORMAT!r}, got {got!r})")
    return payload


def is_finished_with(path: Union[str, Path], cfg: FlockConfig, train_config: dict) -> bool:
    """True when ``path`` holds a controller whose training ran to the end with exactly ``cfg``
    and the training configuration ``train_config`` (a dict, as stored): the load-or-train rule."""
    path = Path(path)
    if not path.is_file():
        return False
    payload = read_checkpoint(path)
    meta = payload["meta"]
    return (payload["config"] == dataclasses.asdict(cfg) and meta.get("train_config") == train_config
            and bool(meta.get("finished")))


def load_controller(path: Union[str, Path], cfg: Optional[FlockConfig] = None, device=None):
    """Rebuild the controller stored at ``path``.

    Args:
        cfg: fly the controller in this configuration instead of the one it was trained in (for
            example another team size N'); by default the stored one.
    Returns: a controller (``reset()``, ``__call__(r, v) -> u``) with ``.meta`` holding the
    training record stored beside the weights.
    """
    payload = read_checkpoint(path)
    spec, stored_cfg = payload["spec"], FlockConfig(**payload["config"])
    kind = spec.get("kind")
    if kind == "dagnn":
        from .models import AggregationMLP, DAGNNController

        model = AggregationMLP(spec["K"], spec["F"], spec["hidden"])
        _load_weights(model, payload["state_dict"], path)
        controller = DAGNNController(model.to(device).eval(), cfg or stored_cfg, spec["gso"],
                                     spec["feature_transform"])
    elif kind == "vgai":
        from .models import AggregationMLP, VGAIController, VGAIModel, VisionConfig, VisualCNN

        c = spec["cnn"]
        cnn = VisualCNN(c["in_channels"], c["height"], c["width"], spec["F"], c["widths"], c["hidden"])
        model = VGAIModel(cnn, AggregationMLP(spec["K"], spec["F"], spec["hidden"]))
        _load_weights(model, payload["state_dict"], path)
        controller = VGAIController(model.to(device).eval(), cfg or stored_cfg,
                                    VisionConfig.from_dict(spec["vision"]), spec["gso"])
    else:
        raise ValueError(f"{path}: unknown controller kind {kind!r} (expected 'dagnn' or 'vgai')")
    controller.meta = payload["meta"]
    controller.trained_config = stored_cfg
    return controller


def _load_weights(model: torch.nn.Module, state_dict: dict, path) -> None:
    try:
        model.load_state_dict(state_dict, strict=True)
    except RuntimeError as exc:
        raise ValueError(f"{path}: the stored weights do not match the stored architecture "
                         f"({str(exc).splitlines()[0]}); the file is inconsistent, train again") from exc
