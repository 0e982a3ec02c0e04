"""vgai_lite.lab: the reproduction and the book's tooling, built on the method (``vgai_lite``).

  the book's models  ``runs`` (the shipped DAGNNs, estimators and VGAIs by name), ``provenance`` (what a
                     record says about where it came from)
  the paper's tables ``paper`` (its numbers), ``table_cells``, ``reproduce``, ``ray_runner`` (the same on Ray)
  chapter 08         ``perturbations`` (what goes wrong in flight), ``robustness`` (the sweep)
  the book's prose   ``findings`` (sentences computed from records), ``paper_vs_book`` (the table of choices)
  the course         ``exercises``, ``method_exercises``, ``experiment_exercises`` (the checks),
                     ``course`` (student copies, grading)
  tooling            ``viz3d`` (the 3-D flight player, meshcat), ``benchmark``, ``website``, ``chromium`` (headless Chromium over DevTools), ``pdf``
                     (the book printed), ``cli`` (``python -m vgai_lite COMMAND``)

Nothing in ``vgai_lite`` imports from here.
"""

from .runs import book_dagnn, book_estimator, book_vgai

__all__ = ["book_dagnn", "book_estimator", "book_vgai"]
