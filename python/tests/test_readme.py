"""The README's Python section runs as written, from the clone's root (it reads a fixture; every
output goes to temporary folders)."""
import re


def test_readme_python_section_runs(root, monkeypatch, capsys):
    text = (root / "README.md").read_text()
    section = text[text.index("\n## Python\n"):]
    section = section[: section.index("\n## ", 1)]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 1, "the README's Python section has one python block"
    monkeypatch.chdir(root)
    exec(compile(blocks[0], "README.md (Python)", "exec"), {"__name__": "__readme__"})
    out = capsys.readouterr().out
    assert "561 nodes" in out and "completed" in out and "contact.compliance -" in out
    assert "('max_penetration', " in out
