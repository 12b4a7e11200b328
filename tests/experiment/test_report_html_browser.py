#!/usr/bin/env python3
"""ctest ReportHtml.*: report.html in a real browser (headless Chromium through Selenium).

    python3 tests/experiment/test_report_html_browser.py --scatterlab build/bin/scatterlab \\
        --artefacts build/tests/report_html_browser [--docs-screenshot docs/images/x.png]

Runs a tiny experiment (data/scenes/glow.json at 64x48: the exact reference, per-voxel and
gradient), opens its report.html from the file system (file://) in headless Chromium and checks:
the page loads with no console message of level SEVERE (the browser's log); keys 1-9 switch the
image and the displayed canvas pixels change; exposure +1 stop (two presses of '+') doubles the
displayed linear values with the linear tone map; the relative error map of the reference against
itself is black everywhere (and of a run against it is not); the split view shows one image left
and the other right of the split; the metrics table sorts and a row opens its image; the pixel
readout shows the values under the pointer. Saves a screenshot (report_html.png) in --artefacts.

Exit 77 (ctest: skipped) only when the packages are absent: python3-selenium, chromium,
chromium-driver (scripts/test.sh installs them).
"""
import argparse
import base64
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
DRIVER = shutil.which("chromedriver") or (
    "/usr/bin/chromedriver" if os.path.exists("/usr/bin/chromedriver") else None)

try:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import Select
    HAVE_SELENIUM = True
except ImportError:
    HAVE_SELENIUM = False

if not (HAVE_SELENIUM and CHROMIUM and DRIVER):
    if not HAVE_SELENIUM and os.path.exists("/usr/bin/python3") and \
            os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") and \
            subprocess.run(["/usr/bin/python3", "-c", "import selenium"],
                           capture_output=True).returncode == 0:
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    missing = [p for p, ok in (("python3-selenium", HAVE_SELENIUM), ("chromium", CHROMIUM),
                               ("chromium-driver", DRIVER)) if not ok]
    print("SKIPPED: no " + ", ".join(missing) + " (scripts/test.sh installs them)")
    sys.exit(77)

# Exposure +1 stop must double the displayed linear values. The canvas holds 8-bit sRGB, so the
# ratio of two decoded values is off by the quantisation: over the channels whose linear value
# at 0 stops is in [0.1, 0.45] (doubled: not clipped), |ratio / 2 - 1| measured at most 0.0155
# (2026-11-26, Chromium 156, 56160 channels of the tiny experiment); allowed: 0.023 (x1.5).
EXPOSURE_LO, EXPOSURE_HI, EXPOSURE_TOL = 0.1, 0.45, 0.023

# Escaped by the page writer: in the data element and in <title>.
TITLE = "report.html browser test </script><!-- & <b>"
# Inline Markdown is rendered (as DOM nodes, never HTML); a link to anything but http(s) or a
# relative path stays text.
DESCRIPTION = ("A `code` word, **bold**, *em*, a [link](report.md), "
               "[no script](javascript:alert(1)) and <b>not bold</b>.")
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def srgb_to_linear(v):
    v /= 255.0
    return v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4


def run_experiment(cli, work):
    cfg = {
        "title": TITLE,
        "description": DESCRIPTION,
        "scene": os.path.join(ROOT, "data", "scenes", "glow.json"),
        "set": ["camera.width=64", "camera.height=48", "medium.resolution=16"],
        "references": ["exact"],
        "repetitions": 1,
        "warmup": 0,
        "methods": ["per-voxel", "gradient"],
    }
    path = os.path.join(work, "exp.json")
    with open(path, "w") as f:
        json.dump(cfg, f)
    out = os.path.join(work, "out")
    r = subprocess.run([cli, "experiment", path, "-o", out, "-q"], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("scatterlab experiment failed (exit %d):\n%s%s" % (r.returncode, r.stdout, r.stderr))
    page = os.path.join(out, "report.html")
    if not os.path.exists(page):
        sys.exit("scatterlab experiment wrote no " + page)
    return page


def start_browser(profile):
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1280,1100", "--user-data-dir=" + profile, "--no-first-run"):
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(executable_path=DRIVER), options=opts)


def wait_idle(driver):
    driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "window.scatterlabReport.idle().then(() => done(true), (e) => done(String(e)));")


def canvas_pixels(driver, viewer=0):
    """The displayed canvas of a viewer: (width, height, RGBA bytes)."""
    wait_idle(driver)
    w, h, b64 = driver.execute_script(
        "const c = window.scatterlabReport.viewers[arguments[0]].canvas;"
        "const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;"
        "let s = ''; for (let i = 0; i < d.length; i += 8192)"
        "  s += String.fromCharCode.apply(null, d.subarray(i, i + 8192));"
        "return [c.width, c.height, btoa(s)];", viewer)
    return w, h, base64.b64decode(b64)


def opaque(px):
    return [i for i in range(0, len(px), 4) if px[i + 3] == 255]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scatterlab", required=True)
    ap.add_argument("--artefacts", required=True, help="directory for the screenshot")
    ap.add_argument("--docs-screenshot", help="also save the screenshot here")
    ap.add_argument("--page", help="test this report.html instead of a fresh tiny experiment "
                                   "(its first viewer needs a reference and two runs)")
    args = ap.parse_args()
    if not args.page and not os.access(args.scatterlab, os.X_OK):
        sys.exit("--scatterlab %s: not an executable" % args.scatterlab)
    os.makedirs(args.artefacts, exist_ok=True)
    work = tempfile.mkdtemp(prefix="scatterlab_report_html_")
    try:
        page = os.path.abspath(args.page) if args.page else run_experiment(args.scatterlab, work)
        if not os.path.isfile(page):
            sys.exit("--page %s: no such file" % page)
        driver = start_browser(os.path.join(work, "profile"))
        try:
            test_page(driver, page, args)
        finally:
            driver.quit()
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if failures:
        print("%d check(s) failed" % len(failures))
        return 1
    print("all checks passed")
    return 0


def test_page(driver, page, args):
    driver.get("file://" + page)
    t0 = time.time()
    while not driver.execute_script("return !!window.scatterlabReport") and time.time() < t0 + 30:
        time.sleep(0.1)
    check(driver.execute_script("return !!window.scatterlabReport"), "the page's script ran")
    if not args.page:
        check(driver.title == TITLE and
              driver.find_element(By.TAG_NAME, "h1").text == TITLE, "the title, escaped")
    if not args.page:
        desc = driver.find_element(By.CSS_SELECTOR, "p.description")
        tags = driver.execute_script(
            "return [...arguments[0].children].map(e => e.tagName + ':' + e.textContent)", desc)
        check(tags == ["CODE:code", "STRONG:bold", "EM:em", "A:link"],
              "the description's Markdown rendered, the script link and the HTML left as text: %s"
              % tags)
        check("javascript:alert(1)" in desc.text and "<b>not bold</b>" in desc.text,
              "the unsafe parts shown as text")
    wait_idle(driver)
    # The overview: one thumbnail per image of each viewer, the PNGs beside the EXRs, loaded.
    thumbs = driver.execute_script(
        "return [...document.querySelectorAll('.overview .thumb img')]"
        ".map(i => i.complete && i.naturalWidth > 0)")
    n_items = driver.execute_script(
        "return window.scatterlabReport.viewers.reduce((n, v) => n + v.items.length, 0)")
    check(len(thumbs) == n_items and all(thumbs),
          "overview: %d thumbnails loaded for %d images" % (sum(thumbs), n_items))
    check(driver.execute_script("return window.scatterlabReport.viewers[0].tone") == "linear",
          "the viewers' default tone map is the PNGs' (linear)")
    viewers = driver.execute_script("return window.scatterlabReport.viewers.length")
    check(viewers >= 1, "at least one viewer (%d)" % viewers)
    items = driver.execute_script(
        "return window.scatterlabReport.viewers[0].items.map(i => i.kind)")
    check(len(items) >= 3 and items[0] == "reference", "viewer 0: a reference and two runs: %s" % items)
    body = driver.find_element(By.TAG_NAME, "body")
    root = driver.find_element(By.ID, "viewer-0")
    Select(root.find_element(By.CSS_SELECTOR, "select.tone")).select_by_value("linear")

    def press(keys):
        body.send_keys(keys)
        wait_idle(driver)

    # Switching: keys 2 and 3 show the two runs, 1 the reference; each changes the pixels.
    press("2")
    w, h, p2 = canvas_pixels(driver)
    press("3")
    _, _, p3 = canvas_pixels(driver)
    press("1")
    _, _, p1 = canvas_pixels(driver)
    lit = opaque(p2)
    check(len(lit) > 0.2 * w * h, "the image covers the canvas (%d of %d px)" % (len(lit), w * h))
    for name, a, b in (("2 -> 3", p2, p3), ("3 -> 1", p3, p1), ("2 -> 1", p2, p1)):
        changed = sum(1 for i in lit if a[i:i + 3] != b[i:i + 3])
        check(changed > 0.01 * len(lit), "key switch %s changes displayed pixels (%d of %d)"
              % (name, changed, len(lit)))
    selected = driver.execute_script("return window.scatterlabReport.viewers[0].a")
    check(selected == 0, "key 1 selects item 0 (got %s)" % selected)

    # Exposure: +1 stop (two presses of '+', 0.5 stop each) doubles the linear values.
    press("2")
    _, _, e0 = canvas_pixels(driver)
    press("+")
    press("+")
    exposure = driver.execute_script("return window.scatterlabReport.viewers[0].exposure")
    check(exposure == 1, "two '+' presses: exposure +1 stop (%s)" % exposure)
    _, _, e1 = canvas_pixels(driver)
    worst, n = 0.0, 0
    for i in lit:
        for c in range(3):
            a = srgb_to_linear(e0[i + c])
            if EXPOSURE_LO <= a <= EXPOSURE_HI:
                worst = max(worst, abs(srgb_to_linear(e1[i + c]) / a / 2 - 1))
                n += 1
    check(n > 50, "channels in [%g, %g] to compare: %d" % (EXPOSURE_LO, EXPOSURE_HI, n))
    check(worst <= EXPOSURE_TOL, "exposure +1: displayed linear values x2 within %g (worst %.4f)"
          % (EXPOSURE_TOL, worst))
    press("-")
    press("-")

    # The error map: of a run against the reference it shows something; of the reference
    # against itself it is black.
    mode = Select(root.find_element(By.CSS_SELECTOR, "select.mode"))
    mode.select_by_value("error")
    wait_idle(driver)
    _, _, err_run = canvas_pixels(driver)
    coloured = sum(1 for i in lit if err_run[i] or err_run[i + 2])
    check(coloured > 0, "error map of run 2 against the reference: %d coloured px" % coloured)
    check(all(err_run[i + 1] == 0 for i in lit), "error map: no green")
    press("1")
    _, _, err_self = canvas_pixels(driver)
    nonzero = sum(1 for i in lit if err_self[i:i + 3] != b"\0\0\0")
    check(nonzero == 0, "error map of the reference against itself is zero (%d non-black px)"
          % nonzero)
    press("e")  # back to the image
    check(mode.first_selected_option.get_attribute("value") == "image", "key e toggles the map")

    # Split: shift+3 splits the image shown (2) against 3; left of the split the one, right the
    # other.
    press("2")
    press(Keys.SHIFT + "3")
    b = driver.execute_script("return window.scatterlabReport.viewers[0].b")
    check(b == 2, "shift+3 splits against item 2 (%s)" % b)
    _, _, split = canvas_pixels(driver)
    sx = w // 2
    left = right = bad = 0
    for i in lit:
        x = (i // 4) % w
        if abs(x - sx) <= 2:
            continue
        want = p2 if x < sx else p3
        if split[i:i + 3] != want[i:i + 3]:
            bad += 1
        elif x < sx:
            left += 1
        else:
            right += 1
    check(bad == 0 and left > 0 and right > 0,
          "split at 0.5: left image 2, right image 3 (%d px wrong)" % bad)
    press(Keys.SHIFT + "3")
    check(driver.execute_script("return window.scatterlabReport.viewers[0].b") == -1,
          "shift+3 again ends the split")

    # The pixel readout: the values under the pointer, image and reference.
    canvas = root.find_element(By.CSS_SELECTOR, "canvas")
    ActionChains(driver).move_to_element(canvas).perform()
    readout = root.find_element(By.CSS_SELECTOR, ".readout").text
    check("pixel (" in readout and "image" in readout and "reference" in readout
          and "relative error" in readout, "readout under the pointer: %r" % readout)

    # The table: sorting by time puts the rows in order; a row opens its image.
    headers = driver.find_elements(By.CSS_SELECTOR, "table.metrics th")
    names = [th.text for th in headers]
    col = names.index("time (ms)") if "time (ms)" in names else -1
    check(col >= 0, "the table has a time column: %s" % names)
    if col >= 0:
        headers[col].click()
        times = [float(tr.find_elements(By.TAG_NAME, "td")[col].text)
                 for tr in driver.find_elements(By.CSS_SELECTOR, "table.metrics tbody tr")]
        check(times == sorted(times), "sorted by time: %s" % times)
        check(headers[col].get_attribute("aria-sort") == "ascending", "aria-sort ascending")
    rows = driver.find_elements(By.CSS_SELECTOR, "table.metrics tbody tr.has-image")
    check(len(rows) >= 2, "rows with images: %d" % len(rows))
    if rows:
        run = rows[-1].get_attribute("data-run")
        rows[-1].click()
        wait_idle(driver)
        shown = driver.execute_script(
            "const r = window.scatterlabReport.data.table.rows.find(r => r.run === arguments[0]);"
            "const v = window.scatterlabReport.viewers[r.group]; return v.items[v.a].run", run)
        check(shown == run, "clicking row %s shows its image (%s)" % (run, shown))

    # The screenshot: the first viewer, its first run split against the reference, the values
    # under the pointer.
    driver.execute_script("window.scatterlabReport.viewers[0].root.scrollIntoView()")
    driver.execute_script("window.scatterlabReport.viewers[0].activate()")
    press("2")
    press(Keys.SHIFT + "1")
    ActionChains(driver).move_to_element_with_offset(canvas, 40, 20).perform()
    shot = os.path.join(args.artefacts, "report_html.png")
    driver.save_screenshot(shot)
    print("screenshot: " + shot)
    if args.docs_screenshot:
        shutil.copyfile(shot, args.docs_screenshot)

    # Last: the console. SEVERE entries are errors (uncaught exceptions, failed loads).
    logs = driver.get_log("browser")
    for e in logs:
        print("console %s: %s" % (e.get("level"), e.get("message")))
    severe = [e for e in logs if e.get("level") == "SEVERE"]
    check(not severe, "no console errors (%d SEVERE of %d messages)" % (len(severe), len(logs)))


if __name__ == "__main__":
    sys.exit(main())
