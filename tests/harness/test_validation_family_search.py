"""``--family-search`` of the validation runs reaches the backbone's options."""

import pytest

from mmshbm.cli.common import Usage
from validation.__main__ import _proximal, build_parser


@pytest.mark.parametrize("command", ["corpus", "exact"])
def test_the_family_search_is_a_backbone_option_of_the_corpus_and_exact_runs(command):
    parser = build_parser()
    assert _proximal(parser.parse_args([command, "3", "--family-search", "deflated"])) == {
        "family_search": "deflated"}
    assert "family_search" not in _proximal(parser.parse_args([command, "3"]))
    with pytest.raises(Usage):
        parser.parse_args([command, "3", "--family-search", "other"])
