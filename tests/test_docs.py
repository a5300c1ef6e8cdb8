"""Documentation that is generated from the code stays in sync with it."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_case_reference_is_generated_from_the_schema():
    r = subprocess.run([sys.executable, str(ROOT / "docs" / "generate_cases_md.py"), "--check"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_every_case_key_is_documented():
    from bearingsim.case import SCHEMA

    text = (ROOT / "docs" / "cases.md").read_text()
    assert SCHEMA and all(section.keys for section in SCHEMA.values())
    for section in SCHEMA.values():
        for key in section.keys:
            assert f"`{key}`" in text, key
