# %% [markdown]
# # 10 · Appendix: the reproduction on Ray
#
# *Beyond the paper: how the book's one command scales past one machine.*
#
# Notebook 07 regenerates the paper's tables on one machine. This appendix shows the same command
# run as Ray tasks, what it measured on this machine, and how long the full reproduction would take
# on several.

# %%
import json

from IPython.display import Markdown, display

from vgai_lite.book import DATA_DIR, prose
from vgai_lite.lab.reproduce import load_results

results = load_results()  # the committed full run: data/results/results.json

# %% [markdown]
# ## Past one machine
#
# A full reproduction with three training seeds per VGAI row takes the hours projected below on one
# laptop. The same
# command runs its trainings and cells as [Ray](https://docs.ray.io) tasks (`vgai_lite/lab/ray_runner.py`):
#
# ```bash
# pip install -r requirements-cluster.txt                  # Ray, an optional group
# python -m vgai_lite reproduce --ray --threads 1          # a local Ray instance: one task per core
# ray start --head                                         # on a cluster: the head machine ...
# ray start --address HEAD:6379                            # ... and each worker (same repository, same environment)
# python -m vgai_lite reproduce --ray auto --vgai-seeds 3  # then from the head
# ```
#
# Each training and each cell is one task that declares as many CPUs as the torch threads it runs
# with; a cell waits for its model through the training task's reference, and the three VGAIs of
# Table 1b that share a first stage train one after another. The tasks call the same functions and
# write the same files as the serial loop, so with the same threads per task the numbers are the
# same (a test checks it on the quick run), and an interrupted run resumes from what is on disk. On a
# cluster the results folder must be one that every machine sees (a shared filesystem).
#
# **Measured on this machine, and projected.** `python tools/experiments/ray_quick.py` times the quick
# reproduction (every table in miniature, from scratch) serially and on a local Ray instance of two
# CPUs; `vgai_lite.lab.ray_runner.projected_hours` projects the full reproduction on M machines of two
# cores from the times recorded in this run's cells (each model's training time from its record,
# each cell's evaluation time), with three training seeds per VGAI row. The projection is the larger
# of the work spread evenly over the machines and the longest chain that must run in order (the three
# VGAIs of Table 1b that share a first stage, then the slowest cell); it ignores Ray's own overhead
# and assumes every machine is this one. Each training's time is the one its record holds (how it ran
# is in the record's provenance, and most VGAI trainings shared the two cores with another job, which
# makes them slower than alone: notebook 06 times the recipe alone). So the projection is an estimate:
# the shared-core trainings push it up, Ray's own overhead (measured below) pushes it down.

# %%
from vgai_lite.lab.ray_runner import projected_hours

rq = json.loads((DATA_DIR / "experiments" / "ray_quick.json").read_text())
display(prose("The quick run, alone on this {cpus}-core machine (`{cmd}`): **{s2:.0f} s** serially with two torch "
              "threads (the command's default), {s1:.0f} s serially with one, and **{r:.0f} s** on Ray (two CPUs, one "
              "thread per task, {tasks} tasks): {ratio:.2f}× the default serial run. The Ray run's tables are "
              "{eq} the one-thread serial run's. {why}",
              cpus=rq["cpus"], cmd=rq["command"], s2=rq["serial_2_threads_seconds"], s1=rq["serial_1_thread_seconds"],
              r=rq["ray_seconds"], ratio=rq["ray_over_serial"], tasks=rq["ray"]["tasks"]["trainings"] + rq["ray"]["tasks"]["cells"],
              eq="identical to" if rq["ray_equals_serial_1_thread"] else "NOT identical to",
              why=("On two cores Ray does not win: the serial run already keeps both cores busy with two threads, and Ray "
                   "adds its start-up and its workers' imports; it pays once there are more cores than one task can use."
                   if rq["ray_over_serial"] >= 1 else
                   "Even on two cores Ray wins a little: two one-thread tasks at once use the cores better than one task "
                   "of two threads, whose small tensors leave the second thread idle much of the time.")))

machines = (1, 2, 4, 8, 16)
proj = [projected_hours(results, DATA_DIR / "results", m) for m in machines]
display(Markdown("| machines (2 cores each) | projected hours, 3 training seeds per VGAI row | speed-up |\n|---|---|---|\n" +
                 "\n".join(f"| {p['machines']} | {p['projected_hours']:.1f} | {proj[0]['projected_hours'] / p['projected_hours']:.1f}× |"
                            for p in proj)))
prose("From {knee} machines on (of those tried) the projection stops falling: the longest chain, {chain:.1f} h (the three "
      "VGAIs of Table 1b, one after the other, then the slowest cell), bounds it. The same run on one machine "
      "is {one:.1f} h of work.",
      knee=next((p["machines"] for p in proj if p["projected_hours"] <= p["longest_chain_hours"] + 1e-9), machines[-1]),
      chain=proj[0]["longest_chain_hours"], one=proj[0]["serial_hours"])

# %% [markdown]
# ## References
#
# * Ray, a framework for distributed Python ([docs.ray.io](https://docs.ray.io)).
