"""Screenshots of a study report and a rehearsal report for the docs (``docs/img/``).

The pictures in the docs come from real runs, made as the docs say:

    transfertwin study run --objects o1,o18 --theta-step 30 --runs 4 --db s.sqlite
    transfertwin analyze s.sqlite --out report
    transfertwin rehearse --plant-seed 1 --objects o3,o7 --calibration-experiments 40 --out reh
    python scripts/report_screenshots.py report/report.html reh/report.html --out docs/img

Debian's chromium, driven by Playwright (``TRANSFERTWIN_CHROMIUM`` overrides its path, as
for the web tests), opens each page at 1280 px wide and photographs its sections:
``study-report-summary.png`` (the advice and the formal answer),
``study-report-full-state.png`` (the first full-state figure with its caption),
``rehearsal-report-findings.png`` (the scores explained and what the rehearsal found) and
``rehearsal-report-truth.png`` (the hidden truth beside the fitted proxy).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

CHROMIUM = os.environ.get("TRANSFERTWIN_CHROMIUM", "/usr/bin/chromium")
#: (page argument, CSS selector, file name)
SHOTS = (
    ("study", "#summary", "study-report-summary.png"),
    ("study", "figure:has(img[alt^='full_state_'])", "study-report-full-state.png"),
    ("rehearsal", "#findings", "rehearsal-report-findings.png"),
    ("rehearsal", "#truth", "rehearsal-report-truth.png"),
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("study", type=Path, help="a study's report.html (transfertwin analyze)")
    parser.add_argument("rehearsal", type=Path, help="a rehearsal's report.html")
    parser.add_argument("--out", type=Path, default=Path("docs/img"), help="output folder")
    args = parser.parse_args(argv)
    for page in (args.study, args.rehearsal):
        if not page.is_file():
            print(f"report_screenshots: no such page {page}", file=sys.stderr)
            return 2
    from playwright.sync_api import sync_playwright

    args.out.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM)
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        for which, selector, name in SHOTS:
            page.goto(getattr(args, which).resolve().as_uri())
            page.locator(selector).first.screenshot(path=str(args.out / name))
            print(args.out / name)
        browser.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
