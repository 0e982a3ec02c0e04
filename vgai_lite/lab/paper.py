"""The paper's section 4 tables: their layout (rows, columns) and the paper's own numbers.

Introduced in notebook 07; notebooks 01, 03 and 06 read the paper's numbers from here too. ``PAPER``
holds the only numbers in the book typed by hand, from the paper's source
(../shared/paper/vgai-corl2020.tex, Tables 1-3); everything else is computed.
"""

from __future__ import annotations

PAPER: dict[str, dict] = {
    "F": {"DAGNN": {6: 1.70}, "VGAI": {6: 2.37, 12: 2.38, 24: 2.26}},
    "K": {"DAGNN": {1: 1.94, 2: 1.82, 3: 1.70}, "VGAI": {1: 2.48, 2: 2.29, 3: 2.26}},
    "v_init": {"DAGNN": {1: 1.58, 2: 1.63, 3: 1.70}, "Local": {1: 3.63, 2: 3.77, 3: 4.13},
               "VGAI": {1: 1.97, 2: 2.10, 3: 2.26}},
    "R": {"DAGNN": {1.0: 1.95, 1.5: 1.70, 2.0: 1.59}, "Local": {1.0: 4.85, 1.5: 4.13, 2.0: 2.75},
          "VGAI": {1.0: 2.65, 1.5: 2.26, 2.0: 1.77}},
    "N": {"VGAI": {50: 1.70, 60: 2.14, 75: 2.23}},
}
"""The paper's numbers (Tables 1-3), by table, row and column. Typed from the paper's source
(../shared/paper/vgai-corl2020.tex, section 4); they are the only hand-typed numbers of the book."""

TABLES: dict[str, dict] = {
    "F": {"title": "Table 1a: feature dimension F (K - 1 = 3)", "column": "F", "columns": [6, 12, 24],
          "rows": ["DAGNN", "VGAI"]},
    "K": {"title": "Table 1b: number of exchanges K - 1 (F = 24)", "column": "K - 1", "columns": [1, 2, 3],
          "rows": ["DAGNN", "VGAI"]},
    "v_init": {"title": "Table 2a: initial velocity v_init [m/s]", "column": "v_init", "columns": [1.0, 2.0, 3.0],
               "rows": ["DAGNN", "DAGNN (retrained)", "Local", "VGAI"]},
    "R": {"title": "Table 2b: communication radius R [m]", "column": "R", "columns": [1.0, 1.5, 2.0],
          "rows": ["DAGNN", "DAGNN (retrained)", "DAGNN (per neighbour)", "Local", "VGAI"],
          "extra_rows": ["VGAI (retrained)"]},
    "N": {"title": "Table 3: trained on N = 50, flown by N' agents", "column": "N'",
          "columns": [50, 60, 75, 100, 200], "rows": ["DAGNN", "DAGNN (per neighbour)", "Local", "VGAI"]},
}
