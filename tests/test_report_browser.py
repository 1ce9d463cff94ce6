"""The nightly page in a real browser: headless Chromium (Debian's `chromium` and
`chromium-driver`) driven by Selenium opens the page of a small real report run
(tests/report_run.py) and checks that every image decoded, that the checks table has one row
per case metric, and that the console logged no error; a screenshot is saved in the test's
temporary folder.

Without chromium/chromedriver the test skips, unless SCOURSPH_REQUIRE_BROWSER=1 (CI, after
.ci/install_browser.sh), in which case it fails.
"""

from __future__ import annotations

import os
import shutil

import pytest
from report_run import EXPECTED_CHECKS, shared_report_run

REQUIRE = os.environ.get("SCOURSPH_REQUIRE_BROWSER", "") == "1"
CHROMIUM = ("chromium", "chromium-browser")
FLAGS = (
    "--headless",
    "--no-sandbox",  # root in a container: the sandbox cannot start
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--window-size=1400,1000",
)


def need_browser():
    browser = next((shutil.which(b) for b in CHROMIUM if shutil.which(b)), None)
    driver = shutil.which("chromedriver")
    try:
        import selenium  # noqa: F401
    except ImportError:
        selenium_missing = True
    else:
        selenium_missing = False
    missing = [
        n
        for n, ok in (("chromium", browser), ("chromedriver", driver), ("selenium", not selenium_missing))
        if not ok
    ]
    if missing:
        msg = (
            f"real-browser test needs {', '.join(missing)} (install: bash .ci/install_browser.sh; "
            "selenium comes with the test extras)"
        )
        if REQUIRE:
            pytest.fail(msg + "; SCOURSPH_REQUIRE_BROWSER=1 makes this an error")
        pytest.skip(msg)
    return browser, driver


@pytest.fixture(scope="module")
def report_run(tmp_path_factory):
    return shared_report_run(tmp_path_factory)


@pytest.fixture
def chromium(tmp_path):
    browser, driver = need_browser()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = browser
    for flag in FLAGS:
        options.add_argument(flag)
    options.add_argument(f"--user-data-dir={tmp_path / 'chromium-profile'}")  # fresh profile each time
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    # an explicit driver: Selenium Manager would otherwise try to download one
    drv = webdriver.Chrome(service=Service(driver), options=options)
    yield drv
    drv.quit()


def test_report_page_in_headless_chromium(report_run, chromium, tmp_path):
    chromium.get(report_run.page.resolve().as_uri())
    assert chromium.execute_script("return document.readyState") == "complete"
    widths = chromium.execute_script(
        "return Array.from(document.images).map(i => [i.alt, i.complete, i.naturalWidth])"
    )
    # 2 case figures, 2 synthetic extra figures... at least one figure per case with a figure
    assert len(widths) >= 6, widths
    broken = [alt for alt, complete, w in widths if not complete or w <= 0]
    assert not broken, f"images that did not load: {broken}"
    rows = chromium.find_elements("css selector", "table#checks tbody tr.check")
    assert len(rows) == EXPECTED_CHECKS
    assert sorted({r.get_attribute("data-case") for r in rows}) == [
        "failing",
        "known",
        "small_hydro",
        "synthetic",
    ]
    problems = chromium.find_elements("css selector", "li.problem")
    assert len(problems) == 5  # failing, raising, segfault, the moved metric, the regressed benchmark
    errors = [e for e in chromium.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
    assert not errors, errors
    height = chromium.execute_script("return document.body.scrollHeight")
    chromium.set_window_size(1400, min(height, 16000))
    shot = tmp_path / "report.png"
    assert chromium.save_screenshot(str(shot)) and shot.stat().st_size > 10_000
    print(f"screenshot: {shot}")
