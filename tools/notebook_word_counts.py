"""Words in the markdown cells of each committed notebook at one or more commits:

    python3 tools/notebook_word_counts.py 07ad35d~1 HEAD
"""
import json, re, subprocess, sys
def counts(rev):
    names = subprocess.run(["git", "ls-tree", "--name-only", rev, "notebooks/"], capture_output=True, text=True).stdout.split()
    out = {}
    for n in names:
        if not n.endswith(".ipynb"): continue
        nb = json.loads(subprocess.run(["git", "show", f"{rev}:{n}"], capture_output=True, text=True).stdout)
        out[n.split("/")[-1][:2]] = sum(len(re.findall(r"\S+", "".join(c["source"]))) for c in nb["cells"] if c["cell_type"] == "markdown")
    return out
for rev in sys.argv[1:]:
    c = counts(rev); print(rev, sum(c.values()), c)
