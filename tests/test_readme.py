"""The README's promises: it starts with the two commands, and its Python example runs."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_starts_with_the_two_commands():
    text = README.read_text()
    first_block = re.search(r"```sh\n(.*?)```", text, re.S)
    assert first_block is not None and text.index("```sh") < 20
    commands = [line.split("#")[0].strip() for line in first_block.group(1).splitlines()]
    assert commands == ["make study", "make test"]
    ci = (README.parent / ".ci" / "run").read_text()
    assert "make test" in ci


def test_readme_python_example_runs(capsys):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    assert len(blocks) >= 2
    namespace: dict[str, object] = {}
    for block in blocks:  # in order, in one namespace, as a reader would type them
        exec(compile(block, "README.md", "exec"), namespace)
    printed = capsys.readouterr().out.split()
    assert printed[0] == "True"


def _synopsis() -> dict[str, set[str]]:
    """The options of each command in the README's command-line synopsis."""
    text = README.read_text()
    section = text[text.index("## Command line") :]
    block = re.search(r"```sh\n(.*?)```", section, re.S)
    assert block is not None
    commands: dict[str, set[str]] = {}
    for line in block.group(1).splitlines():
        words = line.split("#")[0].split()
        assert words[0] == "emdm", line
        commands[words[1]] = set(re.findall(r"(--[a-z][a-z0-9-]*)", " ".join(words[2:])))
    return commands


def _parser_options() -> dict[str, set[str]]:
    import argparse

    from emdm.cli.main import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {
        name: {
            option
            for action in command._actions
            if action.help is not argparse.SUPPRESS
            for option in action.option_strings
            if option not in ("-h", "--help")
        }
        for name, command in sub.choices.items()
    }


def test_readme_synopsis_matches_help():
    """Every command and option of --help is in the README's synopsis, and nothing else."""
    assert _synopsis() == _parser_options()
