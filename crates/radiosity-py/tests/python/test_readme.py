"""The README's Python example runs as printed."""

from pathlib import Path

README = Path(__file__).resolve().parents[4] / "README.md"


def test_the_readme_example_runs():
    text = README.read_text()
    block = text.split("<!-- python-example:begin -->")[1].split("<!-- python-example:end -->")[0]
    code = block.split("```python")[1].split("```")[0]
    exec(compile(code, str(README), "exec"), {})
