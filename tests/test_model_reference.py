"""The model reference lives in the repository (issue 34, item 3).

The package, the docs, the README, the notebooks, the case files, the benchmarks and the tests cite
``docs/model.md`` (the model) and ``docs/reference-data.md`` (published values), never a file
outside the repository, and every section they cite exists.  Pure text checks: well under a second.
"""
import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODEL = ROOT / "docs" / "model.md"
REFERENCE = ROOT / "docs" / "reference-data.md"
OLD_MODEL = "MODEL" + ".md"        # the retired name, built so that this file does not cite it

# "docs/model.md section 4", "sections 3-5", "§5–6", "section 1 and 4", "section 8, 9", "10/11"
CITATION = re.compile(r"docs/model\.md(?:'s)?\s*(?:sections?\s+|§\s*)"
                      r"(\d+(?:\s*(?:-|–|,|/|and|§)\s*\d+)*)")


def cited_files(root=ROOT):
    """Every text a user reads or runs: (relative path, text); notebooks as their cells' sources."""
    paths = [root / "README.md", *root.glob("docs/*.md"), *root.glob("docs/*.py"),
             *root.glob("bearingsim/**/*.py"), *root.glob("tests/**/*.py"), *root.glob("benchmarks/*.py"),
             *root.glob("cases/**/*.toml"), *root.glob("notebooks/*.ipynb")]
    out = []
    for p in sorted(set(paths)):
        text = p.read_text(encoding="utf-8")
        if p.suffix == ".ipynb":
            text = "\n".join("".join(c.get("source", [])) for c in json.loads(text)["cells"])
        out.append((p.relative_to(root).as_posix(), text))
    return out


def outside_citations(files):
    """(file, line, text) of every citation of a reference outside the repository: the retired
    MODEL file, or reference-data.md without its docs/ folder (a relative Markdown link target
    ``](reference-data.md`` from inside docs/ is in the repository)."""
    bad = []
    for name, text in files:
        if name == "tests/test_model_reference.py":
            continue
        for k, line in enumerate(text.splitlines(), 1):
            stripped = line.replace("docs/reference-data.md", "")
            if name.startswith("docs/"):
                stripped = stripped.replace("](reference-data.md", "")
            if OLD_MODEL in line or "reference-data.md" in stripped:
                bad.append((name, k, line.strip()))
    return bad


def model_sections(text):
    return {int(m) for m in re.findall(r"^## (\d+)\. ", text, re.M)}


def cited_sections(files):
    """(file, number) of every section number cited as docs/model.md section N / §N."""
    out = []
    for name, text in files:
        for m in CITATION.finditer(text):
            out += [(name, int(n)) for n in re.findall(r"\d+", m.group(1))]
    return out


def test_the_model_reference_is_in_the_repository():
    text = MODEL.read_text(encoding="utf-8")
    assert model_sections(text) == set(range(1, 12)), "docs/model.md keeps sections 1-11"
    for source in ("Jones", "Harris", "Hamrock", "ISO/TS 16281", "ISO 281", "ISO 76", "Smith",
                   "Sawalhi", "Randall", "seed paper"):
        assert source in text, f"docs/model.md names its source {source!r}"
    assert "$$" in text and "## Sources" in text
    assert REFERENCE.is_file()


def test_nothing_cites_a_reference_outside_the_repository():
    """Before issue 34 the code and docs cited a MODEL file and reference-data.md that only lived
    next to the repository (a clone had neither); outputs printed them too."""
    bad = outside_citations(cited_files())
    assert not bad, "cite docs/model.md / docs/reference-data.md instead:\n" + \
        "\n".join(f"{f}:{k}: {line}" for f, k, line in bad[:30])


def test_every_cited_section_exists():
    sections = model_sections(MODEL.read_text(encoding="utf-8"))
    cites = cited_sections(cited_files())
    assert len(cites) > 50, "the citations are found (the pattern still matches how the code cites)"
    missing = [(f, n) for f, n in cites if n not in sections]
    assert not missing, f"docs/model.md has no such section: {missing[:20]}"


def test_the_checker_catches_what_it_must():
    """The two checks above on made-up texts: they flag an outside citation and a section that does
    not exist, and accept the forms the repository uses."""
    files = [("bearingsim/x.py", f"the rule of {OLD_MODEL} section 3"),
             ("docs/a.md", "see ../shared/reference-data.md"),
             ("docs/b.md", "[docs/reference-data.md](reference-data.md), docs/reference-data.md"),
             ("README.md", "docs/model.md sections 3-5, docs/model.md §5–6, docs/model.md section 1 and 4; "
                           "docs/model.md\nsection 12")]
    assert [(f, k) for f, k, _ in outside_citations(files)] == [("bearingsim/x.py", 1), ("docs/a.md", 1)]
    assert [n for f, n in cited_sections(files) if f == "README.md"] == [3, 5, 5, 6, 1, 4, 12]


def test_the_real_record_table_keeps_the_layout_test_realdata_reads():
    """tests/test_realdata.py reads the two outer-race rows of docs/reference-data.md (seven cells);
    it skips without the records, so the layout is checked here."""
    rows = {}
    for line in REFERENCE.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 7:
            rows[cells[0]] = cells[1:]
    for label in ("outer 0.007 in @6:00, 12 kHz (130)", "outer 0.021 in @6:00, 12 kHz (234)"):
        assert label in rows and all(rows[label]), label
