"""The one YAML loader (pincal._yaml): what it accepts and what it refuses, naming the file."""

from __future__ import annotations

import pytest

from pincal._yaml import MAX_NODES, load_yaml, parse_yaml
from pincal.errors import InputFileError, InputLimitError, ModelFileError
from pincal.model import read_sidecar


def test_small_aliases_and_merge_overrides_are_plain_yaml():
    text = "b: &b {a: 0, k: 1}\nx: {m1: &m1 {<<: *b, a: 1}}\ny: {<<: *m1, c: 2}\nz: *b\n"
    assert parse_yaml(text, "f") == {
        "b": {"a": 0, "k": 1},
        "x": {"m1": {"a": 1, "k": 1}},
        "y": {"a": 1, "k": 1, "c": 2},
        "z": {"a": 0, "k": 1},
    }


def test_expansion_is_counted_per_alias_use_and_refused():
    levels = ["l0: &l0 [" + ", ".join(["x"] * 10) + "]"]
    levels += [f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 10) + "]" for i in range(1, 12)]
    with pytest.raises(InputLimitError, match=f"doc.yaml expands to more than {MAX_NODES}"):
        parse_yaml("\n".join(levels), "doc.yaml")  # 10¹² nodes if expanded
    # the same bomb through merge keys (which really copy at construction)
    merges = ["m0: &m0 {" + ", ".join(f"k{j}: {j}" for j in range(10)) + "}"]
    merges += [
        f"m{i}: &m{i} {{<<: [" + ", ".join([f"*m{i - 1}"] * 10) + "]}" for i in range(1, 12)
    ]
    with pytest.raises(InputLimitError):
        parse_yaml("\n".join(merges), "doc.yaml")


@pytest.mark.parametrize(
    ("text", "error", "match"),
    [
        ("a: &a [*a]\n", InputFileError, "refers to its own anchor"),
        ("[" * 5000 + "]" * 5000, InputLimitError, "nests"),
        ("x: " + "9" * 5000 + "\n", InputFileError, "cannot be read"),
        ("a: !!python/object/apply:os.system [ls]\n", InputFileError, "not valid YAML: line 1"),
        ("a: 1\n---\nb: 2\n", InputFileError, "not valid YAML"),
        ("a: [1, 2\n", InputFileError, "not valid YAML"),
        ("\x1f", InputFileError, "not valid YAML"),
        ("1: a\n0x1: b\n", InputFileError, "key 1 is given twice"),
    ],
)
def test_refusals_are_pincal_errors_naming_the_document(text, error, match):
    with pytest.raises(error, match=match) as exc:
        parse_yaml(text, "doc.yaml")
    assert "doc.yaml" in str(exc.value) and len(str(exc.value)) < 400


def test_sidecar_errors_are_model_file_errors_naming_the_file(tmp_path):
    side = tmp_path / "m.yaml"
    side.write_bytes(b"name_mot: [a]\nview_up: \xff\n")
    with pytest.raises(ModelFileError, match=r"m.yaml is not UTF-8 text \(byte 0xff"):
        read_sidecar(side)
    side.write_text("name_mot: [a]\nname_mot: [b]\n")
    with pytest.raises(ModelFileError, match="m.yaml line 2: key 'name_mot' is given twice"):
        read_sidecar(side)
    side.write_text("- a\n- b\n")
    with pytest.raises(ModelFileError, match="m.yaml must be a mapping"):
        read_sidecar(side)
    assert load_yaml(side, "list") == ["a", "b"]


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        # a merged anchor that itself holds a merge is taken fully built (PyYAML 6.0.4
        # gives a: 0 here, 6.0.3 a: 1; YAML 1.1 says the merged mapping's own value)
        ("b: &b {a: 0}\nm: &m {<<: *b, a: 1}\ny: {<<: *m}\n", {"a": 1}),
        # three levels, each overriding one key
        (
            "a: &a {p: 1, q: 1, r: 1}\nb: &b {<<: *a, q: 2}\nc: &c {<<: *b, r: 3}\n"
            "y: {<<: *c}\n",
            {"p": 1, "q": 2, "r": 3},
        ),
        # in a merged list the earlier mapping wins; keys written in place win over all
        ("b: &b {a: 0}\nc: &c {a: 5, q: 1}\ny: {<<: [*b, *c]}\n", {"a": 0, "q": 1}),
        ("b: &b {a: 0}\nc: &c {a: 5, q: 1}\ny: {q: 9, <<: [*c, *b]}\n", {"a": 5, "q": 9}),
        # a merge inside a list of merges is resolved first
        ("b: &b {a: 0}\nm: &m {<<: *b, a: 1}\nc: &c {a: 2, z: 0}\ny: {<<: [*m, *c]}\n",
         {"a": 1, "z": 0}),
    ],
)
def test_nested_merges_follow_yaml_1_1_whatever_the_pyyaml_release(text, expected):
    assert parse_yaml(text, "f")["y"] == expected


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("a: 1\ny: {<<: *x}\n", "not valid YAML"),
        ("a: &a [1, 2]\ny: {<<: *a}\n", "merge key '<<' must name a mapping"),
        ("y: {[1, 2]: 3}\n", "keys must be scalars"),
    ],
)
def test_bad_merges_and_keys_are_refused_naming_the_line(text, match):
    with pytest.raises(InputFileError, match=match):
        parse_yaml(text, "doc.yaml")
