"""``ancf-report --existing DIR ...``: a report on runs that were made already, saying what was run.

A run is compared with the paper's Table 1 only when it *is* the paper's model: its resolved
model (results.h5 ``/model/fingerprint``, io/restart.py) equals that of the paper's config at its
pretwist, and the probes Table 1 reads are the paper's (``probe_difference``).  Anything else (a
subject's own tendon, ψ = 30°, another element count, a bundle, a section-mean probe) gets its own
table of the levels it reached, without a comparison.  An interrupted or failed run is reported
as such: the levels reached, the levels not reached, the level a figure draws.
"""
from __future__ import annotations

import glob
import os


import yaml

from ..config.conditions import parse_probes
from ..config.parse import load_config
from ..config.values import ConfigError
from ..errors import InputError
from ..status import LEVELS_PASSED_OVER
from ..io.h5fast import open_file
from ..io.levels import ended_words, not_asked, step_at
from ..io.reader import check_levels, read_results
from ..io.restart import fingerprint, first_difference
from ..model.build import build_model
from ..physics.elements import ELEMENTS
from .inputs import TWISTS, PaperInputs
from .run_outputs import interface_markdown, probe_markdown, run_figures, support_markdown

__all__ = ["ExistingRun", "levels_missing", "other_figures", "paper_summaries", "probe_difference",
           "read_existing", "runs_markdown", "title"]

#: what a fingerprint item (io/restart.py) is, in words: "<beam>'s ..." for a beam's items
DIFFERENCE_WORDS = {
    "elements": "{beam} has another number of elements",
    "element": "{beam} has another element",
    "axial_points_locking": "{beam} has other axial Gauss points or another locking remedy",
    "material": "{beam} has another material", "fibres": "{beam} has other fibres",
    "x_nodes": "{beam} has other nodes along x", "section_points": "{beam} has another cross-section",
    "section_weights": "{beam} has another cross-section", "connectivity": "{beam} has other elements",
    "reference_nodal_vectors": "the geometry differs", "supported_dofs": "the supports differ",
    "loads": "the loads differ (the paper pulls the soleus end along x)",
    "length": "the tendon length differs", "twist_deg": "the pretwist differs",
    "prescribed_displacements": "a support moves (displacement control)",
    "contact": "the contact differs"}


def _runs_inside(directory: str) -> str:
    """What to do about a directory without summary.json: run ancf-solve, or, for a sweep's or
    study's top directory (which said only that), give the run directories it holds."""
    runs = sorted(os.path.relpath(os.path.dirname(p), directory)
                  for p in glob.glob(os.path.join(directory, "*", "summary.json"))
                  + glob.glob(os.path.join(directory, "*", "*", "summary.json")))
    if not runs:
        return "run ancf-solve first"
    return (f"it holds {len(runs)} run director{'y' if len(runs) == 1 else 'ies'}, e.g. {runs[0]}: give "
            f"those, e.g. --existing {os.path.join(directory, os.path.dirname(runs[0]), '*')}")


class ExistingRun:
    """One run directory: its summary, whether it is the paper's model and why not."""

    def __init__(self, directory: str, inputs: PaperInputs):
        self.dir = directory
        path = os.path.join(directory, "summary.json")
        if not os.path.isdir(directory):
            what = "not a directory" if os.path.exists(directory) else "no such directory"
            raise InputError("--existing", f"{directory}: {what} (give ancf-solve output directories)")
        if not os.path.exists(path):
            raise InputError("--existing", f"{path}: no summary.json ({_runs_inside(directory)})")
        try:
            # read_results: a run still 'running' (or killed) gets the levels results.h5 holds
            # beyond summary.json's, as read_results and --restart see them
            self.summary = read_results(directory).summary
            check_levels(directory, self.summary)
        except InputError as exc:
            raise InputError("--existing", exc.message) from None
        s = self.summary
        self.name = s.get("name", os.path.basename(directory))
        self.status = s.get("status", "unknown")
        self.twist = s.get("twist_deg")
        self.levels = [st["load_factor"] for st in s.get("steps", [])]
        self.config = self._config()
        self.why_not = self._paper_difference(inputs)

    def _config(self) -> dict:
        """The run's config as written into results.h5 (empty when it cannot be read)."""
        try:
            with open_file(os.path.join(self.dir, "results.h5"), "r") as f:
                raw = yaml.safe_load(f["model"].attrs["config_yaml"])
        except (OSError, KeyError, yaml.YAMLError):
            return {}
        return raw if isinstance(raw, dict) else {}

    @property
    def is_paper(self) -> bool:
        return self.why_not is None

    @property
    def psi(self) -> int | None:
        return int(round(self.twist)) if self.twist is not None else None

    def _paper_difference(self, inputs: PaperInputs) -> str | None:
        """None when the run's model is the paper's at its pretwist, else what differs."""
        if self.twist is None:
            return "its summary gives no pretwist (twist_deg)"
        if not any(abs(self.twist - p) < 1e-9 for p in TWISTS):
            return f"ψ = {self.twist}° is not one of the paper's {', '.join(f'{p}°' for p in TWISTS)}"
        h5 = os.path.join(self.dir, "results.h5")
        try:
            with open_file(h5, "r") as f:
                if "fingerprint" not in f["model"]:
                    return "results.h5 has no model fingerprint (written by an older version)"
                stored = {}
                f["model/fingerprint"].visititems(
                    lambda n, o: stored.__setitem__(n, o[()]) if hasattr(o, "shape") else None)
        except (OSError, KeyError) as exc:
            return f"{h5}: not readable ({exc})"
        spec = load_config(os.path.join(inputs.configs, f"achilles_type3_psi{self.psi}.yaml"))
        paper = fingerprint(build_model(spec))
        differs = first_difference(paper, stored)
        if differs is not None and differs[0].endswith("/elements") and differs[1] not in ("added", "removed"):
            return "its model is not the paper's: " + element_counts(paper, stored)
        if differs is not None:
            return "its model is not the paper's: " + difference_words(*differs)
        return probe_difference(spec, self.config)

    def ended(self) -> str:
        """How the run ended, in words."""
        s = self.summary
        text = f"{self.status}"
        if self.status == "running":
            text += " (no final status: still running, or killed)"
        elif self.status != "completed" or s.get("reason_code") == LEVELS_PASSED_OVER:
            text += f" ({s.get('reason_code', '')}: {s.get('message', '')})"
        return text


def difference_words(key: str, detail: str) -> str:
    """A fingerprint difference (``io.restart.first_difference``) in words."""
    beam, _, item = key.rpartition("/")
    beam = beam.removeprefix("beams/")
    if detail in ("added", "removed") and beam:
        return f"beam {beam} is {'not in' if detail == 'added' else 'missing from'} the paper's model"
    if item.startswith("load_curve"):
        return "a load or displacement follows a load curve"
    words = DIFFERENCE_WORDS.get(item, f"{key} differs").format(beam=beam)
    return f"{words} ({detail})" if item in ("elements", "element", "length", "twist_deg", "contact") else words


def probe_difference(paper, config: dict) -> str | None:
    """Where the run's probes that Table 1 reads (the paper config's ``probes``, by name) are not
    the paper's nodal vector at the paper's node, in words; None when they are.  ``paper`` is the
    paper config's spec, whose beams the run's model has (its fingerprint is the paper's)."""
    if not config:
        return "its config cannot be read from results.h5, so its probes are not known"
    names = [b.name for b in paper.beams]
    blocks = [ELEMENTS[b.element].block for b in paper.beams]
    n_nodes = [blk.nodes_of(b.elements) for b, blk in zip(paper.beams, blocks)]
    try:
        ours = {p.name: p for p in parse_probes(config.get("probes") or [], names, n_nodes, blocks)}
    except ConfigError as exc:
        return f"its probes cannot be read ({exc})"

    def what(p) -> str:
        return f"vector {p.vector} at node {p.node} of {names[p.beam]}"
    for p in paper.probes:
        q = ours.get(p.name)
        if q is None:
            return f"it has no probe {p.name!r}, which Table 1 reads ({what(p)})"
        if (q.beam, q.node, q.vector) != (p.beam, p.node, p.vector):
            return f"its probe {p.name!r} is {what(q)}, not the paper's {what(p)}, which Table 1 reads"
    return None


def element_counts(paper: dict, stored: dict) -> str:
    """Every beam whose element count differs from the paper's, in words (in the paper's order)."""
    keys = [k for k in paper if k.endswith("/elements") and k in stored and int(paper[k]) != int(stored[k])]
    changed = [(k.removeprefix("beams/").rpartition("/")[0], int(paper[k]), int(stored[k])) for k in keys]
    if len(changed) == 1:
        return difference_words(f"beams/{changed[0][0]}/elements", f"{changed[0][1]} → {changed[0][2]}")
    beams = [f"{b} ({a} → {n})" for b, a, n in changed]
    return ", ".join(beams[:-1]) + f" and {beams[-1]} have other numbers of elements"


def read_existing(dirs: list[str], inputs: PaperInputs) -> list[ExistingRun]:
    return [ExistingRun(d, inputs) for d in dirs]


def runs_markdown(runs: list[ExistingRun]) -> str:
    """What each run is and how it ended, then the levels of the runs that are not the
    paper's model (those are compared in Table 1)."""
    lines = ["| run | model | ψ | status | levels reached |", "|---|---|---:|---|---:|"]
    for r in runs:
        twist = "?" if r.twist is None else f"{r.twist:g}"
        lines.append(f"| {r.dir} | {r.name}{'' if r.is_paper else ' (not the paper’s model)'} | "
                     f"{twist} | {r.ended()} | {len(r.levels)} |")
    for r in runs:
        if r.is_paper:
            continue
        lines += ["", f"**{r.dir}** is not compared with the paper: {r.why_not}.", ""]
        if not r.summary.get("steps"):
            lines.append("No converged level.")
            continue
        lines += (probe_markdown(r.summary, r.config) + interface_markdown(r.summary, r.config)
                  + support_markdown(r.summary))
    return "\n".join(lines)


def other_figures(runs: list[ExistingRun], out: str) -> list[str]:
    """The figures of the runs that are not the paper's model (``run_outputs.run_figures``); two
    runs of one model name get the run's place in the list too (the second's figures overwrote
    the first's, and the report linked one file twice)."""
    others = [r for r in runs if not r.is_paper]
    names = [r.name for r in others]
    stems = [f"{r.name}_{k}" if names.count(r.name) > 1 else None for k, r in enumerate(others, start=1)]
    return [f for r, stem in zip(others, stems) for f in run_figures(r.dir, r.summary, r.config, out, stem)]


def shadowed(runs: list[ExistingRun]) -> str:
    """The paper runs Table 1 leaves out: an earlier one of two at the same pretwist (the last
    given is the column), in words (empty when none)."""
    last = {r.psi: r for r in runs if r.is_paper}
    left = [f"{r.dir} (ψ = {r.psi}°: {last[r.psi].dir} is the column)" for r in runs
            if r.is_paper and last[r.psi] is not r]
    return "; ".join(left)


def title(runs: list[ExistingRun]) -> str:
    """The report's title: the paper's reproduction only when a run is the paper's model."""
    if any(r.is_paper for r in runs):
        return "Type III Achilles tendon: reproduction of Obrezkov et al. (2022)"
    return "Runs of " + ", ".join(dict.fromkeys(r.name for r in runs)) + " (not the paper's model)"


def paper_summaries(runs: list[ExistingRun]) -> dict[int, dict]:
    """ψ → summary of the runs that are the paper's model (the last one given per ψ)."""
    out = {}
    for r in runs:      # its files are where it was given: summary.json's output_dir is where it ran
        if r.is_paper:
            out[r.psi] = dict(r.summary, output_dir=os.path.abspath(r.dir))
    return out


def levels_missing(t1, summaries: dict) -> str:
    """The Table 1 levels a paper run did not reach, per column (empty when every one did)."""
    parts = []
    for p, s in summaries.items():       # a level passed over in a gap is reached (Table 1's †)
        missing = [float(f) for f in t1.loads if step_at(s.get("steps", []), float(f)) is None]
        unasked = [f for f in missing if not_asked(s, f)]
        if unasked:
            parts.append(f"ψ = {p}°: not asked {', '.join(f'{f:g}' for f in unasked)} N (not among the run's "
                         "steps)")
        if len(missing) > len(unasked):
            parts.append(f"ψ = {p}°: not reached {', '.join(f'{f:g}' for f in missing if f not in unasked)} N "
                         f"({ended_words(s)})")
    return "; ".join(parts)

