"""Every malformed scene of the C corpus (tests/corpus/manifest.txt) that is valid JSON, given to
mpm.Simulation as a dict, raises mpm.SceneError with the message `mpm check` prints: the same
key path and the same expectation."""

import json
import os

import pytest

import mpm
from conftest import ROOT

CORPUS = os.path.join(ROOT, "tests", "corpus")


class Duplicate(Exception):
    pass


def no_duplicates(pairs):
    keys = [k for k, _ in pairs]
    if len(keys) != len(set(keys)):
        raise Duplicate()
    return dict(pairs)


def cases():
    """(file, expected pieces) of the corpus cases a dict can carry: valid JSON (no NaN
    literals, no duplicate keys: a dict cannot hold those), exit 2, not heavy, a message that
    does not point into the text (line and column refer to the file's own layout), and in the
    double build none of the float build's range refusals."""
    out = []
    with open(os.path.join(CORPUS, "manifest.txt")) as f:
        for line in f:
            if not line.strip() or line.startswith("#"):
                continue
            fields = line.rstrip("\n").split("\t")
            name, code, expected = fields[0], fields[1], fields[2]
            flags = fields[3] if len(fields) > 3 else ""
            if code != "2" or "heavy" in flags or "known_bug" in flags:
                continue
            if "line " in expected or "column" in expected:
                continue
            if "float build" in expected and mpm.real_type() != "float":
                continue  # what only the float build's range refuses
            path = name if os.path.isabs(name) else os.path.join(CORPUS, name)
            if not path.endswith(".json"):
                continue
            try:
                with open(path, encoding="utf-8") as g:
                    scene = json.load(g, object_pairs_hook=no_duplicates,
                                      parse_constant=lambda c: (_ for _ in ()).throw(Duplicate()))
            except (ValueError, Duplicate, UnicodeDecodeError, OSError):
                continue
            if not isinstance(scene, dict):
                continue
            out.append(pytest.param(scene, expected.split(" ... "), id=os.path.basename(name)))
    return out


CASES = cases()


def test_the_corpus_has_dict_cases():
    assert len(CASES) > 100


@pytest.mark.parametrize("scene,pieces", CASES)
def test_scene_error_names_the_key_path(scene, pieces):
    with pytest.raises(mpm.SceneError) as caught:
        mpm.Simulation(scene, base_dir=os.path.relpath(CORPUS))  # as `mpm check` names it
    message = str(caught.value)
    # a dict holds the number, not its text: -0 becomes -0.0 in the JSON, which the engine
    # reports as 0
    pieces = [p.replace("got -0", "got 0") if p.endswith("got -0") else p for p in pieces]
    at = 0
    for piece in pieces:
        found = message.find(piece, at)
        assert found >= 0, f"{piece!r} not in {message!r}"
        at = found + len(piece)


def test_non_finite_numbers_in_a_dict():
    from conftest import small_scene
    scene = small_scene()
    scene["materials"][0]["E"] = float("nan")
    with pytest.raises(mpm.SceneError, match=r"materials\[0\]\.E: expected a number, got NaN"):
        mpm.Simulation(scene)
    scene["materials"][0]["E"] = float("inf")  # what json.load makes of 1e400
    with pytest.raises(mpm.SceneError,
                       match=r"materials\[0\]\.E: .*too large to represent"):
        mpm.Simulation(scene)
    # the word in a string is left alone
    scene = small_scene(name="Infinity")
    assert mpm.Simulation(scene).info["particles"] > 0


def test_scene_of_the_wrong_type():
    with pytest.raises(TypeError):
        mpm.Simulation(42)
    with pytest.raises(mpm.SceneError, match="expected a JSON object"):
        mpm.Simulation("[1, 2]")
