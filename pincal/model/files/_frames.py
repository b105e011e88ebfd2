"""Choosing the measured frame when neither the caller nor the sidecar names one.

Public closed-loop models often end their URDF with a closure frame (a leg tip or a
platform anchor), so "the last leaf link" is a poor default. The rule here:

1. a link named like an effector, by token (``effector``/``ee``/``tcp`` before
   ``tool``/``probe`` before ``flange`` before ``platform``), closure links excluded;
   among equals the shortest name (fewest tokens) wins;
2. else the leaf link farthest from the root (in joints) that carries no closure;
3. else (a tie) an error that lists the candidates.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from pincal.errors import ModelFileError
from pincal.model.files._urdf import UrdfTree

__all__ = ["EFFECTOR_WORDS", "default_measured_frame", "measured_frame_candidates"]

#: effector-like name tokens, best first (one group per priority)
EFFECTOR_WORDS: tuple[tuple[str, ...], ...] = (
    ("effector", "endeffector", "ee", "eef", "tcp"),
    ("tool", "probe"),
    ("flange",),
    ("platform",),
)


def _tokens(name: str) -> list[str]:
    return [re.sub(r"\d+$", "", t) for t in re.split(r"[^a-z0-9]+", name.lower()) if t]


def _rank(link: str) -> tuple[int, int] | None:
    """(priority group, number of tokens) of an effector-like name, else None."""
    toks = _tokens(link)
    for rank, words in enumerate(EFFECTOR_WORDS):
        if any(t in words for t in toks):
            return rank, len(toks)
    return None


def _groups(tree: UrdfTree, closure_links: Iterable[str]) -> tuple[list, list, list]:
    """(effector-named links best first, leaves deepest first, other links deepest first)."""
    excluded = set(closure_links) | {tree.root_link}
    links = [link for link in tree.links if link not in excluded]
    named = sorted((r, link) for link in links if (r := _rank(link)) is not None)
    parents = {j.parent for j in tree.joints.values()}
    by_depth = sorted(links, key=lambda link: -len(tree.ancestors(link)))
    leaves = [link for link in by_depth if link not in parents]
    others = [link for link in by_depth if link in parents]
    return named, leaves, others


def measured_frame_candidates(tree: UrdfTree, closure_links: Iterable[str]) -> list[str]:
    """Candidate measured frames, best first.

    Effector-named links come first, then leaves and then the other links, deepest first
    (closure links and the root excluded).
    """
    named, leaves, others = _groups(tree, closure_links)
    ordered = [link for _, link in named]
    return ordered + [link for link in leaves + others if link not in ordered]


def default_measured_frame(tree: UrdfTree, closure_links: Iterable[str], model_name: str) -> str:
    """The measured frame chosen by the rule of this module.

    Raises:
        ModelFileError: the choice is not clear (the message lists the candidates).
    """
    closure_links = set(closure_links)
    named, leaves, _ = _groups(tree, closure_links)
    if named:
        best = [link for r, link in named if r == named[0][0]]
    elif leaves:
        depth = len(tree.ancestors(leaves[0]))
        best = [link for link in leaves if len(tree.ancestors(link)) == depth]
    else:
        best = []
    if len(best) == 1:
        return best[0]
    candidates = measured_frame_candidates(tree, closure_links)
    why = (
        f"{', '.join(map(repr, best))} are equally likely"
        if best
        else "no link is named like an effector and every leaf link carries a closure"
    )
    listed = ", ".join(map(repr, candidates[:10])) or "none"
    raise ModelFileError(
        f"cannot choose the measured frame of {model_name!r}: {why} (candidates: {listed}); "
        f"choose one with --frame (measured_frame= in Python) or 'measured_frame' in the sidecar"
    )
