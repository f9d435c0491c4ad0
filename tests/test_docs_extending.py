"""The pages stay true: the tutorial's code is the example plug-in's, the leaf and its test
fit in 40 lines, and the configuration page names every key of the schema."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bearchair.executive.mission_config import MissionConfig

ROOT = Path(__file__).resolve().parents[1]
SNIPPET = re.compile(r"<!-- snippet: (?P<path>\S+) -->\n```\w*\n(?P<code>.*?)```", re.DOTALL)
LEAF = "examples/bearchair-example-plugin/bearchair_example/leaves.py"
LEAF_TEST = "examples/bearchair-example-plugin/tests/test_example_leaf.py"


def snippets() -> dict[str, str]:
    return {
        m["path"]: m["code"] for m in SNIPPET.finditer((ROOT / "docs/extending.md").read_text())
    }


def test_the_tutorial_shows_the_leaf_and_its_test():
    assert {LEAF, LEAF_TEST} <= set(snippets())


@pytest.mark.parametrize("path", sorted(snippets()))
def test_each_snippet_of_the_tutorial_is_its_file(path):
    assert snippets()[path] == (ROOT / path).read_text(), f"docs/extending.md shows an old {path}"


def test_the_tutorial_leaf_and_its_test_fit_in_40_lines():
    lines = sum(len((ROOT / path).read_text().splitlines()) for path in (LEAF, LEAF_TEST))
    assert lines <= 40


def test_the_configuration_page_names_every_key():
    page = (ROOT / "docs/configuration.md").read_text()
    for section, field in MissionConfig.model_fields.items():
        assert f"## [{section}]" in page, section
        model = field.annotation
        assert model is not None
        for key in model.model_fields:
            assert f"`{key}`" in page, f"[{section}] {key} is not on docs/configuration.md"
