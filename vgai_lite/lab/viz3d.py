"""meshcat 3-D views of a swarm, exported as standalone HTML that works offline.

Introduced in notebook 04. meshcat 0.3.2 starts a server subprocess per ``meshcat.Visualizer()``;
``vis.close()`` does not exist there and the server outlives its parent, so every visualizer here is
opened by ``meshcat_visualizer()``, a context manager that always stops its server. The returned HTML
inlines the whole viewer (about 0.9 MB) and the scene, animation included: no server, no network.
"""

from __future__ import annotations

import html as html_lib
from contextlib import contextmanager

import numpy as np

from ..config import FlockConfig
from ..flocking import Trajectory
from ..render import RenderConfig


@contextmanager
def meshcat_visualizer():
    """A meshcat Visualizer whose server subprocess is stopped on exit, whatever happens inside."""
    import contextlib
    import io

    import meshcat

    with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints a URL that dies with the server
        vis = meshcat.Visualizer()
    try:
        yield vis
    finally:
        proc = getattr(vis.window, "server_proc", None)
        if proc is not None:
            proc.kill()
            proc.wait(timeout=10)


def swarm_scene_html(traj: Trajectory, cfg: FlockConfig, b: int = 0, every: int = 2,
                     altitude: float = 1.0, rcfg: RenderConfig = RenderConfig(),
                     trails: bool = True, links: bool = True) -> str:
    """Standalone HTML of an animated 3-D view of swarm ``b`` of a trajectory.

    Drones are spheres of the body radius at a common ``altitude`` (the paper flies them on one
    height plane); ``trails`` draws each drone's path; ``links`` draws the communication graph of
    the last frame. One animation frame every ``every`` steps, played in real time.
    """
    import meshcat.geometry as g
    import meshcat.transformations as tf
    from meshcat.animation import Animation

    r = traj.r[:, b].detach().cpu().double().numpy()  # (T, N, 2)
    T, N, _ = r.shape
    z = np.full((T, N, 1), altitude)
    p = np.concatenate((r, z), axis=-1)
    center = p[0].mean(axis=0)
    p = p - center * np.array([1, 1, 0])  # start the swarm's centre above the origin
    with meshcat_visualizer() as vis:
        vis["/Axes"].set_property("visible", False)
        # look down on the swarm from above and behind (the camera's frame is y-up, as in three.js)
        vis["/Cameras/default/rotated/<object>"].set_property("position", [-4.0, 7.0, 5.0])
        body = g.Sphere(rcfg.body_radius * 1.5)
        for i in range(N):
            vis[f"swarm/drone_{i:03d}"].set_object(body, g.MeshLambertMaterial(color=0x1F77B4))
            vis[f"swarm/drone_{i:03d}"].set_transform(tf.translation_matrix(p[0, i]))
            if trails:
                vis[f"trails/{i:03d}"].set_object(
                    g.Line(g.PointsGeometry(p[:, i].T.astype(np.float32)),
                           g.LineBasicMaterial(color=0x9ECAE1)))
        if links:
            last = p[-1]
            d = np.linalg.norm(last[:, None, :2] - last[None, :, :2], axis=-1)
            ii, jj = np.nonzero(np.triu(d <= cfg.R, k=1))
            if len(ii):
                seg = np.stack((last[ii], last[jj]), axis=1).reshape(-1, 3).T.astype(np.float32)
                vis["links_at_end"].set_object(
                    g.LineSegments(g.PointsGeometry(seg), g.LineBasicMaterial(color=0xBBBBBB)))
        anim = Animation(default_framerate=max(1, round(1.0 / (cfg.Ts * every))))
        for frame, t in enumerate(range(0, T, every)):
            with anim.at_frame(vis, frame) as fv:
                for i in range(N):  # animate positions only (no rotation): half the data
                    fv[f"swarm/drone_{i:03d}"].set_property("position", "vector3", [float(x) for x in p[t, i]])
        vis.set_animation(anim, play=True, repetitions=1)
        return vis.static_html()


def iframe(html: str, height: int = 420) -> str:
    """Wrap standalone HTML in an iframe (for ``IPython.display.HTML``), isolated from the notebook."""
    return (f'<div><iframe srcdoc="{html_lib.escape(html, quote=True)}" style="width: 100%; '
            f'height: {height}px; border: none"></iframe></div>')
