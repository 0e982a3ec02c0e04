"""The book's files: learned controllers and stand-alone state estimators. One file holds the
configuration, the architecture and the weights.

Introduced in notebook 03. Files are written atomically (a temporary file renamed into place, so an
interrupted run never leaves half a file) with ``torch.save`` and read with
``torch.load(..., weights_only=True)``: only tensors and plain values, so loading never runs code.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path
from typing import Callable, Optional, Union

import torch

from .book import shipped_file
from .config import FlockConfig
from .learned_controllers import DAGNNController, VGAIController
from .models import AggregationMLP, VGAIModel, VisualCNN, cnn_from_spec
from .vision import VisionConfig

FORMAT = "vgai-lite-controller/1"
ESTIMATOR_FORMAT = "vgai-lite-estimator/1"


def config_hash(obj) -> str:
    """12 hex digits identifying a JSON-able object (keys sorted): names cache files and table cells."""
    return hashlib.sha1(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:12]


def atomic_save(payload: dict, path: Union[str, Path]) -> Path:
    """``torch.save`` to a temporary file beside ``path``, then rename it into place."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    torch.save(payload, tmp)
    tmp.replace(path)
    return path


def weights(module: torch.nn.Module) -> dict:
    return {k: t.detach().cpu() for k, t in module.state_dict().items()}


def save_controller(path: Union[str, Path], controller, meta: Optional[dict] = None) -> Path:
    """Write ``controller`` (it must have ``spec()``, ``model`` and ``cfg``) and ``meta`` to ``path``."""
    payload = {"format": FORMAT, "spec": controller.spec(), "config": dataclasses.asdict(controller.cfg),
               "state_dict": weights(controller.model), "meta": meta or {}}
    return atomic_save(payload, path)


def read_checkpoint(path: Union[str, Path]) -> dict:
    """The raw payload of a checkpoint file, with clear errors for missing or corrupt files."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no checkpoint at {path}: train one first (see notebook 03, "
                                f"vgai_lite.load_or_train) or check the path")
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:
        raise ValueError(f"{path} is not a readable vgai-lite checkpoint ({type(exc).__name__}: {exc}); "
                         f"delete it and train again") from exc
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        got = payload.get("format") if isinstance(payload, dict) else type(payload).__name__
        raise ValueError(f"{path} is not a vgai-lite controller checkpoint (expected format {FORMAT!r}, got {got!r})")
    return payload


def is_finished_with(path: Union[str, Path], cfg: FlockConfig, train_config: dict,
                     read: Optional[Callable[[dict], dict]] = None) -> bool:
    """True when ``path`` holds a controller whose training ran to the end with exactly ``cfg``
    and the training configuration ``train_config`` (a dict, as stored): the load-or-train rule.
    ``read``: the stored configuration in today's form (the configuration class's ``read_stored``:
    fields added after the file was written take the value it was trained with)."""
    path = Path(path)
    if not path.is_file():
        return False
    payload = read_checkpoint(path)
    meta = payload["meta"]
    stored = meta.get("train_config")
    if isinstance(stored, dict) and read is not None:
        stored = read(stored)
    return payload["config"] == dataclasses.asdict(cfg) and stored == train_config and bool(meta.get("finished"))


SHIPPED_KINDS = ("vgai", "dagnn")


def resolve(path: Union[str, Path]) -> Path:
    """``path`` itself, or, for the name of a controller the book ships (``"vgai_F24"``, ``"dagnn_K4"``),
    its file (``book.shipped_file``: the checkout's data/ or the installed package's copy)."""
    p = Path(path)
    if p.suffix or len(p.parts) > 1 or p.is_file():
        return p
    kind = str(path).split("_")[0]
    if kind not in SHIPPED_KINDS:
        raise ValueError(f"{path!r} is neither a checkpoint file (.pt) nor the name of a shipped controller "
                         f"(vgai_* or dagnn_*, e.g. 'vgai_F24')")
    return shipped_file(f"{kind}/{path}.pt")


def load_controller(path: Union[str, Path], cfg: Optional[FlockConfig] = None, device=None):
    """Rebuild the controller stored at ``path`` (a file, or a shipped controller's name: ``"vgai_F24"``).

    Args:
        cfg: fly the controller in this configuration instead of the one it was trained in (for
            example another team size N'); by default the stored one.
    Returns: a controller (``reset()``, ``__call__(r, v) -> u``) with ``.meta`` holding the
    training record stored beside the weights.
    """
    path = resolve(path)
    payload = read_checkpoint(path)
    spec, stored_cfg = payload["spec"], FlockConfig(**payload["config"])
    kind = spec.get("kind")
    if kind == "dagnn":
        model = AggregationMLP(spec["K"], spec["F"], spec["hidden"])
        load_weights(model, payload["state_dict"], path)
        controller = DAGNNController(model.to(device).eval(), cfg or stored_cfg, spec["gso"],
                                     spec["feature_transform"])
    elif kind == "vgai":
        model = VGAIModel(cnn_from_spec(spec["cnn"], spec["cnn"].get("F", spec["F"])),
                          AggregationMLP(spec["K"], spec["F"], spec["hidden"]), spec.get("readout", "features"))
        load_weights(model, payload["state_dict"], path)
        controller = VGAIController(model.to(device).eval(), cfg or stored_cfg,
                                    VisionConfig.from_dict(spec["vision"]), spec["gso"])
    else:
        raise ValueError(f"{path}: unknown controller kind {kind!r} (expected 'dagnn' or 'vgai')")
    controller.meta = payload["meta"]
    controller.trained_config = stored_cfg
    return controller


def load_weights(model: torch.nn.Module, state_dict: dict, path) -> None:
    try:
        model.load_state_dict(state_dict, strict=True)
    except RuntimeError as exc:
        raise ValueError(f"{path}: the stored weights do not match the stored architecture "
                         f"({str(exc).splitlines()[0]}); the file is inconsistent, train again") from exc


# ---------------------------------------------------------------------------------------------
# Stand-alone visual state estimators (notebook 05): a VisualCNN and what it is shown


def save_estimator(path: Union[str, Path], cnn: VisualCNN, vision: VisionConfig, meta: dict) -> Path:
    payload = {"format": ESTIMATOR_FORMAT, "vision": vision.to_dict(),
               "cnn": {**cnn.spec(), "F": cnn.F},
               "state_dict": weights(cnn), "meta": meta}
    return atomic_save(payload, path)


def load_estimator(path: Union[str, Path]) -> tuple[VisualCNN, VisionConfig, dict]:
    """(cnn, vision, meta) from an estimator file (weights_only: no code runs)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no estimator at {path}: run `python -m vgai_lite train-vgai --estimators`")
    payload = torch.load(path, map_location="cpu", weights_only=True)
    if not isinstance(payload, dict) or payload.get("format") != ESTIMATOR_FORMAT:
        raise ValueError(f"{path} is not a vgai-lite state estimator (format {ESTIMATOR_FORMAT!r})")
    cnn = cnn_from_spec(payload["cnn"], payload["cnn"]["F"])
    load_weights(cnn, payload["state_dict"], path)
    return cnn.eval(), VisionConfig.from_dict(payload["vision"]), payload["meta"]
