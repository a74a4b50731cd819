"""The web view and the API docs in a real headless Chromium (selenium) against a real uvicorn on loopback.

The browser is offline: every host name but 127.0.0.1 resolves to nothing and no proxy is
used (``OFFLINE_ARGS``), as on a shop network without internet, so a page that needed a CDN
would break here (``test_the_browser_is_offline`` shows that it would).

Skipped, with the reason, when selenium, ``chromium`` or ``chromedriver`` is missing (CI
installs the Debian packages in ``.ci/run``). The server gets a temporary store seeded with
the demo measurement; server and browser are always shut down.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.helpers import REPO, start_uvicorn
from tests.service.conftest import wait_until_ready

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed (pip install -e '.[test]')")
from selenium.common.exceptions import TimeoutException  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import Select, WebDriverWait  # noqa: E402

#: Chromium as on a network without internet: no proxy, and no host name but 127.0.0.1 resolves
#: (nothing is sent anywhere: the name lookup itself fails inside the browser).
OFFLINE_ARGS = ("--no-proxy-server", "--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1")
LIBRARY = REPO / "tests" / "data" / "tool-libraries" / "fusion-synthetic" / "synthetic_library.tools"
WAIT_S = 120.0  # generous: a loaded machine is slow, and a pass takes seconds


def _executable(default: str, name: str) -> str | None:
    if Path(default).is_file() and os.access(default, os.X_OK):
        return default
    return shutil.which(name)


CHROMIUM = _executable("/usr/bin/chromium", "chromium")
CHROMEDRIVER = _executable("/usr/bin/chromedriver", "chromedriver")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(CHROMIUM is None, reason="no chromium browser (Debian: apt-get install chromium)"),
    pytest.mark.skipif(CHROMEDRIVER is None, reason="no chromedriver (Debian: apt-get install chromium-driver)"),
]


@pytest.fixture(scope="module")
def server(tmp_path_factory) -> Iterator[str]:
    """Base URL of ``uvicorn service.main:create_app`` on a free loopback port (demo store)."""
    tmp = tmp_path_factory.mktemp("web-server")
    env = {**os.environ, "RCSA_STORE": str(tmp / "store"), "RCSA_SEED_DEMO": "true", "RCSA_ANONYMOUS_READ": "true",
           "RCSA_JOB_POLL_S": "0.2", "MPLCONFIGDIR": str(tmp / "mpl")}
    env.pop("PROMETHEUS_MULTIPROC_DIR", None)
    log_path = tmp / "uvicorn.log"
    proc, base = start_uvicorn(["service.main:create_app", "--factory"], env, log_path)
    try:
        wait_until_ready(base, proc, log_path)
        yield base
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)


@pytest.fixture(scope="module")
def downloads(tmp_path_factory) -> Path:
    """Where the browser saves downloads."""
    return tmp_path_factory.mktemp("web-downloads")


@pytest.fixture(scope="module")
def browser(tmp_path_factory, downloads) -> Iterator[webdriver.Chrome]:
    """Headless Chromium with a fresh profile, offline (``OFFLINE_ARGS``)."""
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--no-first-run", "--window-size=1280,1800",
                f"--user-data-dir={tmp_path_factory.mktemp('chromium-profile')}", *OFFLINE_ARGS):
        options.add_argument(arg)
    options.add_experimental_option("prefs", {"download.default_directory": str(downloads),
                                              "download.prompt_for_download": False})
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(options=options, service=Service(CHROMEDRIVER))
    try:
        driver.set_page_load_timeout(WAIT_S)
        driver.set_script_timeout(WAIT_S)
        yield driver
    finally:
        driver.quit()


# --------------------------------------------------------------------------- helpers

def _wait_state(driver, key: str, want: str = "drawn") -> None:
    """Wait until ``document.body.dataset[key]`` is ``want`` (fail at once on "error")."""
    def done(d):
        value = d.execute_script(f"return document.body.dataset.{key} || ''")
        return value if value in (want, "error") else False

    try:
        value = WebDriverWait(driver, WAIT_S, poll_frequency=0.1).until(done)
    except TimeoutException:
        pytest.fail(f"{key} did not become {want}; page says: {_page_error(driver)!r}")
    assert value == want, f"{key} failed in the page: {_page_error(driver)!r}"


def _page_error(driver) -> str:
    box = driver.find_element(By.ID, "error")
    return box.text if box.is_displayed() else ""


def _points(driver, path_id: str) -> int:
    """Vertices of an SVG path drawn by the page (M and L commands in its d attribute)."""
    d = driver.find_element(By.ID, path_id).get_attribute("d") or ""
    return d.count("L") + d.count("M")


def _severe_console(driver) -> list[str]:
    return [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]


def _wait_download(folder: Path, suffix: str) -> Path:
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        done = [p for p in folder.iterdir() if p.suffix == suffix]
        if done:
            return done[0]
        time.sleep(0.1)
    pytest.fail(f"no {suffix} file was downloaded into {folder}: {[p.name for p in folder.iterdir()]}")


def _open(driver, base: str) -> None:
    driver.get(base + "/")
    WebDriverWait(driver, WAIT_S).until(
        lambda d: d.execute_script("return document.body.dataset.ready === 'true'"))
    assert driver.current_url == base + "/ui/"


# --------------------------------------------------------------------------- tests

def test_predict_ra1_draw_frf_and_lobes_and_download(server, browser, downloads):
    _open(browser, server)
    spindles = [o.text for o in Select(browser.find_element(By.ID, "spindle")).options]
    assert spindles[0].startswith("RA-1") and any("demo-ra1" in s for s in spindles), spindles

    browser.find_element(By.ID, "predict").click()
    _wait_state(browser, "frf")
    for path in ("frf-real-path", "frf-imag-path", "frf-mag-path", "frf-phase-path"):
        assert _points(browser, path) > 4000, path  # 5–5000 Hz by 1 Hz: 4996 lines
    assert "599.85 Hz" in browser.find_element(By.ID, "nat-freqs").text
    assert "N/µm" in browser.find_element(By.ID, "static-stiffness").text
    assert "µm/N at" in browser.find_element(By.ID, "min-real").text
    assert not browser.find_element(By.ID, "lobes").get_attribute("disabled")

    browser.find_element(By.ID, "op-speed").send_keys("12000")
    browser.find_element(By.ID, "op-depth").send_keys("0.2")
    browser.find_element(By.ID, "lobes").click()
    _wait_state(browser, "lobes")
    assert _points(browser, "lobes-envelope-path") >= 250  # the page asks for 300 speeds
    assert browser.find_elements(By.CSS_SELECTOR, "#lobes-plot polygon.stable")
    assert browser.find_elements(By.ID, "operating-point")
    assert " mm (chatter at " in browser.find_element(By.ID, "lobes-min-depth").text
    assert " rpm" in browser.find_element(By.ID, "lobes-pockets").text

    # the semi-discretization at a thin radial cut: the same drawing from the other method
    Select(browser.find_element(By.ID, "lobes-method")).select_by_value("semi_discretization")
    for field, value in (("immersion", "0.05"), ("speed-count", "120")):
        browser.find_element(By.ID, field).clear()
        browser.find_element(By.ID, field).send_keys(value)
    browser.find_element(By.ID, "lobes").click()
    _wait_state(browser, "lobes")
    assert 60 < _points(browser, "lobes-envelope-path") <= 120  # 120 speeds
    # auto at a thin radial cut: the semi-discretization, and the page says why
    Select(browser.find_element(By.ID, "lobes-method")).select_by_value("auto")
    browser.find_element(By.ID, "lobes").click()
    _wait_state(browser, "lobes")
    notes = [li.text for li in browser.find_elements(By.CSS_SELECTOR, "#lobes-notes li")]
    assert notes and notes[0].startswith("method semi_discretization") and "teeth in the cut" in notes[0], notes

    browser.find_element(By.ID, "download-lobes-png").click()
    png = _wait_download(downloads, ".png")
    WebDriverWait(browser, WAIT_S).until(lambda d: png.stat().st_size > 1000)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    browser.find_element(By.ID, "download-frf-csv").click()
    csv_file = _wait_download(downloads, ".csv")
    WebDriverWait(browser, WAIT_S).until(lambda d: csv_file.read_text().count("\n") > 4996)
    assert csv_file.read_text().startswith("frequency_hz,h_real_m_n,h_imag_m_n,")
    assert _severe_console(browser) == []


def test_uncertainty_draws_give_a_band_and_robust_lobes(server, browser, downloads):
    _open(browser, server)
    browser.find_element(By.ID, "draws").clear()
    browser.find_element(By.ID, "draws").send_keys("12")
    browser.find_element(By.ID, "predict").click()
    _wait_state(browser, "frf")
    band = browser.find_element(By.ID, "frf-band").get_attribute("points") or ""
    assert band.count(",") > 8000  # p95 forward and p05 back over 4 996 lines
    browser.find_element(By.ID, "lobes").click()
    _wait_state(browser, "lobes")
    assert _points(browser, "lobes-robust-path") >= 250
    before = {p.name for p in downloads.iterdir()}  # the folder may hold other tests' downloads
    browser.find_element(By.ID, "download-frf-csv").click()

    def banded_csv(_):
        fresh = [p for p in downloads.iterdir() if p.suffix == ".csv" and p.name not in before]
        return fresh and fresh[0].read_text().count("\n") > 4996 and fresh[0]

    header = WebDriverWait(browser, WAIT_S).until(banded_csv).read_text().splitlines()[0]
    assert header.endswith("h_magnitude_p05_m_n,h_magnitude_p50_m_n,h_magnitude_p95_m_n")
    assert _severe_console(browser) == []


def test_the_clamping_model_is_chosen_on_the_page(server, browser):
    """Bonded along the insertion moves RA-1's tool mode (the point joint's 1383.6 Hz goes); a contact
    with an impossible interface stiffness is the server's 422, shown, not a broken page."""
    _open(browser, server)
    Select(browser.find_element(By.ID, "clamping")).select_by_value("bonded")
    for field, value in (("freq-stop", "3000"), ("freq-step", "2")):
        browser.find_element(By.ID, field).clear()
        browser.find_element(By.ID, field).send_keys(value)
    browser.find_element(By.ID, "predict").click()
    _wait_state(browser, "frf")
    text = browser.find_element(By.ID, "nat-freqs").text
    assert "1383.6" not in text, text
    Select(browser.find_element(By.ID, "clamping")).select_by_value("contact")
    browser.find_element(By.ID, "interface-stiffness").clear()
    browser.find_element(By.ID, "interface-stiffness").send_keys("1e30")
    assert _severe_console(browser) == []
    browser.find_element(By.ID, "predict").click()
    _wait_state(browser, "frf", want="error")
    WebDriverWait(browser, WAIT_S).until(lambda d: "interface_stiffness_n_m3" in _page_error(d))
    browser.get_log("browser")  # the refused request's console line is expected here, not in the next test


def test_library_entry_on_measured_spindle_and_errors_shown(server, browser):
    _open(browser, server)
    browser.find_element(By.ID, "library-file").send_keys(str(LIBRARY))
    WebDriverWait(browser, WAIT_S).until(
        lambda d: "2 usable, 2 skipped" in d.find_element(By.ID, "library-status").text)
    entry = Select(browser.find_element(By.ID, "entry"))
    disabled = [o.text for o in entry.options if not o.is_enabled()]
    assert any("no holder" in t for t in disabled), disabled
    entry.select_by_value("00000000-0000-4000-8000-000000000102")  # T2, 2 flutes, inch units
    assert browser.find_element(By.ID, "teeth").get_attribute("value") == "2"
    spindle = Select(browser.find_element(By.ID, "spindle"))
    demo = next(o for o in spindle.options if "demo-ra1" in o.text)
    spindle.select_by_value(demo.get_attribute("value"))

    browser.find_element(By.ID, "predict").click()
    _wait_state(browser, "frf")
    assert _points(browser, "frf-real-path") > 4000
    assert "T2" in browser.find_element(By.ID, "predict-status").text
    assert "Hz" in browser.find_element(By.ID, "nat-freqs").text
    assert _severe_console(browser) == []

    step = browser.find_element(By.ID, "freq-step")
    step.clear()
    step.send_keys("-1")
    browser.find_element(By.ID, "predict").click()
    _wait_state(browser, "frf", want="error")
    WebDriverWait(browser, WAIT_S).until(lambda d: d.find_element(By.ID, "error").is_displayed())
    text = browser.find_element(By.ID, "error").text
    assert "Prediction failed" in text and "frequency.step_hz" in text, text


# --------------------------------------------------------------------------- API docs, offline

_CDN_ASSET = "https://cdn.jsdelivr.net/npm/swagger-ui-dist@5/swagger-ui.css"


def test_the_browser_is_offline(server, browser):
    """The control: in this browser a CDN asset cannot be had (FastAPI's default /docs would be blank)."""
    browser.get(server + "/healthz")
    outcome = browser.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "fetch(arguments[0], {mode: 'no-cors'}).then(() => done('loaded'), e => done('failed: ' + e));",
        _CDN_ASSET)
    assert outcome.startswith("failed"), outcome


def test_swagger_ui_and_redoc_render_offline(server, browser):
    browser.get_log("browser")  # what earlier tests left
    browser.get(server + "/docs")
    # Swagger UI rendered the OpenAPI document: its title and an operation block are in the DOM
    WebDriverWait(browser, WAIT_S).until(
        lambda d: d.find_elements(By.CSS_SELECTOR, "#swagger-ui .opblock-summary-path"))
    title = browser.find_element(By.CSS_SELECTOR, "#swagger-ui .info .title").text
    assert title.startswith("rcsa"), title
    paths = {e.get_attribute("data-path") for e in browser.find_elements(By.CSS_SELECTOR, ".opblock-summary-path")}
    assert {"/v1/tool-point-frf", "/v1/diagnoses"} <= paths, paths
    assert browser.find_elements(By.CSS_SELECTOR, "#swagger-ui .btn.authorize")  # X-API-Key box
    loaded = browser.execute_script("return performance.getEntriesByType('resource').map(e => e.name)")
    assert loaded and all(u.startswith(server) for u in loaded), loaded
    assert _severe_console(browser) == []

    browser.get(server + "/redoc")
    WebDriverWait(browser, WAIT_S).until(lambda d: d.find_elements(By.CSS_SELECTOR, ".api-content h1"))
    assert browser.find_element(By.CSS_SELECTOR, ".api-content h1").text.startswith("rcsa")
    assert browser.find_elements(By.CSS_SELECTOR, ".menu-content li")  # the side menu of operations
    # ReDoc's bundle links its maker's logo (sidebar footer) from its CDN; offline the image
    # hides itself. Everything the page needs came from this service.
    logo = "https://cdn.redoc.ly/redoc/logo-mini.svg"
    loaded = browser.execute_script("return performance.getEntriesByType('resource').map(e => e.name)")
    assert all(u.startswith(server) for u in loaded if u != logo), loaded
    assert [m for m in _severe_console(browser) if logo not in m] == []


# --------------------------------------------------------------------------- diagnosis in the page

def _tap_files(folder: Path) -> list[tuple[float, Path]]:
    """The tap tests of examples/diagnosis.json as CSV files (µm/N, a header naming the units)."""
    doc = json.loads((REPO / "examples" / "diagnosis.json").read_text())
    out = []
    for m in doc["measurements"]:
        mm = 1000 * m["tool"]["stickout_m"]
        rows = ["frequency [Hz],real [um/N],imag [um/N]"]
        rows += [f"{f:g},{re * 1e6:.6e},{im * 1e6:.6e}"
                 for f, re, im in zip(m["frequency_hz"], m["h"]["real"], m["h"]["imag"], strict=True)]
        path = folder / f"tap-{mm:.0f}mm.csv"
        path.write_text("\n".join(rows) + "\n")
        out.append((mm, path))
    return out


def test_diagnosis_of_uploaded_tap_tests(server, browser, tmp_path):
    _open(browser, server)
    browser.get_log("browser")
    for i, (mm, path) in enumerate(_tap_files(tmp_path)):
        browser.find_element(By.ID, f"tap-stickout-{i}").send_keys(f"{mm:g}")
        browser.find_element(By.ID, f"tap-file-{i}").send_keys(str(path))
    Select(browser.find_element(By.ID, "diag-effort")).select_by_value("quick")
    browser.find_element(By.ID, "diagnose").click()
    _wait_state(browser, "diagnosis")
    title = browser.find_element(By.ID, "diag-verdict-title").text
    assert "holder_tool_joint" in title and "identified" in title, title
    assert "dB" in browser.find_element(By.ID, "diag-shrink").text
    cells = browser.find_elements(By.CSS_SELECTOR, "#gap-plot rect.gap-cell")
    assert len(cells) >= 3 and browser.find_elements(By.CSS_SELECTOR, "#gap-plot rect.gap-cell.flagged")
    for i in range(3):
        for kind in ("measured", "base", "corrected"):
            assert _points(browser, f"diag-{kind}-{i}") > 400, (kind, i)  # 561 lines each
    assert _severe_console(browser) == []
