"""The one YAML loader of pincal: safe, bounded, strict about duplicate keys.

Every YAML file pincal reads (model sidecars, ``campaign.yaml``) goes through
:func:`load_yaml`. It reads the file with :func:`pincal._files.read_text` (size cap, no
FIFOs or devices), builds only plain data (no Python objects), refuses a document
whose aliases would expand to more than :data:`MAX_NODES` nodes (a "billion laughs"
alias bomb is a few hundred bytes) or that is nested deeper than :data:`MAX_DEPTH`,
and refuses a mapping that gives the same key twice (YAML would silently keep the
last one), naming the key and both lines.

Mappings, sequences and merge keys (``<<``) are built here, not by PyYAML's
constructor, whose handling of nested merges changed between releases (6.0.3 and
6.0.4 give different values for ``{<<: *m}`` when ``m`` itself holds a merge). The
rules are those of the YAML 1.1 merge-key type: a key written in a mapping overrides
every merged key; a merged mapping is taken as it is fully built (its own merges
resolved first); in a merged sequence ``<<: [*a, *b]``, an earlier mapping overrides
a later one. Scalars (numbers, booleans, dates, null) are still resolved by PyYAML's
safe constructor.
"""

from __future__ import annotations

from collections.abc import Hashable
from pathlib import Path
from typing import Any

import yaml

from pincal._files import read_text
from pincal.errors import InputFileError, InputLimitError, clip

__all__ = ["MAX_DEPTH", "MAX_NODES", "load_yaml", "parse_yaml", "path_text", "shown"]

#: largest number of nodes a document may expand to, aliases counted at every use
MAX_NODES = 200_000
#: deepest nesting of sequences and mappings
MAX_DEPTH = 200
_MERGE_TAG = "tag:yaml.org,2002:merge"
_MAP_TAG = "tag:yaml.org,2002:map"
_SEQ_TAG = "tag:yaml.org,2002:seq"


def shown(value: Any, limit: int = 80) -> str:
    """Bounded text of a parsed value for messages: :func:`~pincal.errors.clip`, quoted."""
    return clip(value, limit, quote=True)


class _DuplicateKey(Exception):
    def __init__(self, key: object, line: int, first: int):
        super().__init__(key, line, first)
        self.key, self.line, self.first = key, line, first


def _check_duplicates(nodes: list[Any], loader: yaml.SafeLoader) -> None:
    """Refuse a mapping that gives a scalar key twice (merge keys ``<<`` excepted).

    Run on the composed graph, before construction flattens merge keys into the
    mappings (a key overridden after a merge is not a duplicate).
    """
    for node in nodes:
        if not isinstance(node, yaml.MappingNode):
            continue
        seen: dict[object, int] = {}
        for key_node, _ in node.value:
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == _MERGE_TAG:
                continue
            key = loader.construct_object(key_node, deep=True)
            line = key_node.start_mark.line + 1
            try:
                if key in seen:
                    raise _DuplicateKey(key, line, seen[key])
                seen[key] = line
            except TypeError:
                continue


def _expanded_size(root: Any, where: str) -> list[Any]:
    """Refuse a node graph that expands to more than MAX_NODES nodes or MAX_DEPTH levels.

    Aliases share their node, so the graph is small even when its expansion is
    astronomically large; sizes are memoised per node, which makes the count linear
    in the graph, not in the expansion.

    Returns:
        Every distinct node of the graph.
    """
    sizes: dict[int, int] = {}
    depths: dict[int, int] = {}
    active: set[int] = set()
    visited: list[Any] = []
    # iterative post-order walk (no recursion limit on deep documents)
    stack: list[tuple[Any, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        nid = id(node)
        if done:
            active.discard(nid)
            kids = _children(node)
            size = 1 + sum(sizes[id(k)] for k in kids)
            depth = 1 + max((depths[id(k)] for k in kids), default=0)
            if size > MAX_NODES:
                raise InputLimitError(
                    f"{where} expands to more than {MAX_NODES} YAML nodes (aliases counted at "
                    "each use; an alias bomb?); write the values out or split the file"
                )
            if depth > MAX_DEPTH:
                raise InputLimitError(
                    f"{where} nests more than {MAX_DEPTH} levels deep; flatten the document"
                )
            sizes[nid], depths[nid] = size, depth
            visited.append(node)
            continue
        if nid in sizes:
            continue
        if nid in active:
            raise InputFileError(
                f"{where}: an alias refers to its own anchor (line {node.start_mark.line + 1}); "
                "a recursive document cannot be read"
            )
        active.add(nid)
        stack.append((node, True))
        stack.extend((k, False) for k in _children(node) if id(k) not in sizes)
    return visited


def _children(node: Any) -> list[Any]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return []


class _Builder:
    """Plain data from a composed node graph, merge keys resolved by YAML 1.1's rules.

    Built values are memoised per node, so an alias yields the object of its anchor
    (as PyYAML does); the graph was bounded by :func:`_expanded_size` beforehand, which
    also bounds the recursion depth here.
    """

    def __init__(self, loader: yaml.SafeLoader):
        self.loader = loader
        self.built: dict[int, Any] = {}

    def build(self, node: Any) -> Any:
        nid = id(node)
        if nid not in self.built:
            if isinstance(node, yaml.MappingNode) and node.tag == _MAP_TAG:
                self.built[nid] = self._mapping(node)
            elif isinstance(node, yaml.SequenceNode) and node.tag == _SEQ_TAG:
                self.built[nid] = [self.build(item) for item in node.value]
            else:  # scalars and the rare typed collections (!!set, !!omap, ...)
                self.built[nid] = self.loader.construct_object(node, deep=True)
        return self.built[nid]

    def _mapping(self, node: yaml.MappingNode) -> dict[Any, Any]:
        own: dict[Any, Any] = {}
        merged: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            if key_node.tag == _MERGE_TAG:
                merged.update(self._merged(value_node))
                continue
            key = self.build(key_node)
            if not isinstance(key, Hashable):
                raise yaml.constructor.ConstructorError(
                    None, None, "a mapping key is a list or a mapping; keys must be scalars",
                    key_node.start_mark,
                )
            own[key] = self.build(value_node)
        return {**merged, **own}

    def _merged(self, value_node: Any) -> dict[Any, Any]:
        """The keys one ``<<`` brings: a mapping, or a sequence of them (earlier wins)."""
        sources = value_node.value if isinstance(value_node, yaml.SequenceNode) else [value_node]
        out: dict[Any, Any] = {}
        for source in reversed(sources):
            value = self.build(source)
            if not isinstance(value, dict):
                raise yaml.constructor.ConstructorError(
                    None, None, "a merge key '<<' must name a mapping or a list of mappings",
                    source.start_mark,
                )
            out.update(value)
        return out


def parse_yaml(text: str, where: str, error: type[InputFileError] = InputFileError) -> Any:
    """Parse YAML ``text`` safely (see the module doc).

    Args:
        text: the document.
        where: what and where it is, for messages (e.g. ``"sidecar 'm.yaml'"``).
        error: the class raised for malformed YAML and duplicate keys.

    Returns:
        The plain data (dict, list, str, int, float, bool, None, dates), or None for an
        empty document.

    Raises:
        InputLimitError: the document expands past :data:`MAX_NODES` nodes or nests
            deeper than :data:`MAX_DEPTH`.
        InputFileError: (or ``error``) not valid YAML, a recursive alias, a duplicate key
            (key and lines named), a value YAML cannot represent (e.g. an integer of
            more than 4300 digits), more than one document.
    """
    loader: yaml.SafeLoader | None = None
    try:
        loader = yaml.SafeLoader(text)
        try:
            node = loader.get_single_node()
        except RecursionError:
            raise InputLimitError(
                f"{where} nests too deeply to read; flatten the document"
            ) from None
        if node is None:
            return None
        _check_duplicates(_expanded_size(node, where), loader)
        return _Builder(loader).build(node)
    except _DuplicateKey as dup:
        raise error(
            f"{where} line {dup.line}: key {shown(dup.key)} is given twice (first on line "
            f"{dup.first}); YAML would keep only the last value, so give each key once"
        ) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = f" line {mark.line + 1}" if mark is not None else ""
        what = clip(exc.problem or exc.context or "syntax error", 120)
        raise error(f"{where} is not valid YAML:{line}: {what}") from None
    except yaml.YAMLError as exc:
        raise error(f"{where} is not valid YAML: {clip(str(exc), 160)}") from None
    except (ValueError, OverflowError) as exc:
        raise error(f"{where} holds a value that cannot be read: {clip(str(exc), 160)}") from None
    finally:
        if loader is not None:
            loader.dispose()


def load_yaml(
    path: str | Path,
    what: str = "YAML file",
    error: type[InputFileError] = InputFileError,
    limit: int | None = None,
) -> Any:
    """Read and parse a YAML file safely (size cap, alias and duplicate-key checks).

    Args:
        path: the file.
        what: what the file is, for messages ("sidecar", "campaign file").
        error: the class raised for unreadable or malformed files (e.g.
            :class:`~pincal.errors.ModelFileError` for a sidecar).
        limit: size cap [bytes]; None uses :func:`pincal._files.max_bytes`.

    Returns:
        The plain data, or None for an empty file.

    Raises:
        InputFileError: (or ``error``) missing, not a regular file, not UTF-8, not valid
            YAML, duplicate keys.
        InputLimitError: too large, or an alias expansion / nesting past the bounds.
    """
    text = read_text(path, what, limit, error)
    return parse_yaml(text, f"{what} {path_text(path)}", error)


def path_text(path: str | Path, limit: int = 80) -> str:
    """A path for messages, cut at the front so the file name always shows."""
    text = clip(str(path), 10 * limit)
    return text if len(text) <= limit else "…" + text[-(limit - 1) :]
