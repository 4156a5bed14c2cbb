"""The Python code of the README and of the documentation pages runs as written: every
```python block of ``README.md`` and of each page of ``docs/`` (in the order of ``mkdocs.yml``'s
navigation), unchanged, in a fresh Python process whose working directory holds the files the
blocks name (``src/`` of this checkout, a ``recordings/`` folder of force records). The blocks
of one page run in order in one namespace (a block may use a name an earlier block of the same
page imported, as a reader's session does); each page starts from an empty namespace, so every
page's examples stand on their own.

The blocks are read from the files at test time, so an edit of a page is what runs here.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"

#: Runs the pages' blocks (JSON list of [page, [blocks]], argv[1]); prints which ran.
RUNNER = """
import json, sys, time
pages = json.loads(open(sys.argv[1], encoding="utf-8").read())
for page, blocks in pages:
    namespace = {"__name__": "__main__"}
    for i, code in enumerate(blocks):
        start = time.process_time()
        exec(compile(code, f"{page} python block {i}", "exec"), namespace)
        print(f"{page} block {i}: ok ({time.process_time() - start:.1f} s of CPU)", flush=True)
"""


def python_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```$", text, flags=re.MULTILINE | re.DOTALL)


def pages() -> list[Path]:
    """README.md, then the documentation pages in the order of mkdocs.yml's navigation."""
    mkdocs = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    nav = re.findall(r"^\s*-\s+[^:]+:\s+(\S+\.md)\s*$", mkdocs, flags=re.MULTILINE)
    return [README, *(DOCS / page for page in nav)]


def test_every_page_in_the_navigation_exists_and_every_python_block_is_found_whole():
    found = pages()
    assert len(found) >= 15
    blocks = []
    for page in found:
        text = page.read_text(encoding="utf-8")
        assert len(python_blocks(text)) == text.count("```python"), page
        blocks += python_blocks(text)
    # the un-jitted gradient of the first session is among them, as written
    assert any(
        "jax.grad(lambda E: rbjax.simulate(1.0, ball.replace(youngs_Pa=E)).contact_time_s)" in b
        for b in blocks
    )


def test_the_python_blocks_run_as_written(tmp_path):
    runs = [
        [str(page.relative_to(ROOT)), python_blocks(page.read_text(encoding="utf-8"))]
        for page in pages()
    ]
    runs = [run for run in runs if run[1]]
    # the working directory: the files the blocks name, as in a checkout of the repository
    (tmp_path / "src").symlink_to(ROOT / "src", target_is_directory=True)
    recordings = tmp_path / "recordings"
    recordings.mkdir()
    for record in sorted((ROOT / "src/rbjax/examples/emulated-rubber-ball").glob("h*_d1.csv")):
        shutil.copy(record, recordings / record.name)
    (tmp_path / "blocks.json").write_text(json.dumps(runs), encoding="utf-8")
    (tmp_path / "runner.py").write_text(RUNNER, encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, "runner.py", "blocks.json"],
        cwd=tmp_path,
        env={**os.environ, "MPLBACKEND": "Agg"},
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-4000:]
    ran = [line.split(":")[0] for line in proc.stdout.splitlines() if " block " in line]
    expected = [f"{page} block {i}" for page, blocks in runs for i in range(len(blocks))]
    assert ran == expected, ran
    assert (tmp_path / "room.png").stat().st_size > 1000  # the room page's res.plot("room.png")
