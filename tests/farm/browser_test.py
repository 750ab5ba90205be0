#!/usr/bin/env python3
"""The coordinator's web page in a real headless Chromium (the Debian `chromium` package).

Starts a coordinator (--http-listen, with a token), submits two jobs with the CLI, opens the page, starts
two workers (paused with SIGSTOP while the first preview and the cancel are checked, so that no step
depends on how fast this machine is), and drives the page over the DevTools protocol
(--remote-debugging-pipe: JSON messages on file descriptors 3 and 4, no websocket needed):
  - job A's page shows its preview, and the preview's pixels change as tasks are accepted;
  - job B (behind A) is cancelled with the page's Cancel button: the page and the API say CANCELLED;
  - job A reaches DONE on its page, with the finished image, b ± error and the acceptance table;
  - a screenshot of A's page is saved (argument 3; docs/screenshots/job-page.png in the repository).
Exit 77 (ctest: skipped) with the reason when no Chromium is installed.

usage: browser_test.py TOOLS_DIR SOURCE_DIR SCREENSHOT.png
"""
import base64
import fcntl
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.request

TOKEN = "browser-test-token"
TIMEOUT = 120  # seconds for any one wait (the steps themselves take a few seconds)


def fail(msg):
    print("FAIL: " + msg, file=sys.stderr)
    sys.exit(1)


def find_chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class DevTools:
    """The DevTools protocol over --remote-debugging-pipe (NUL-terminated JSON, fds 3 and 4)."""

    def __init__(self, binary, workdir):
        to_chrome_r, self.to_chrome = os.pipe()
        self.from_chrome, from_chrome_w = os.pipe()
        # The child's ends above 10, so that moving them to 3 and 4 clobbers nothing.
        to_chrome_r, from_chrome_w = (self._above_10(to_chrome_r), self._above_10(from_chrome_w))
        args = [binary, "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--no-first-run", "--no-default-browser-check", "--disable-extensions", "--hide-scrollbars",
                "--remote-debugging-pipe", "--user-data-dir=" + os.path.join(workdir, "chrome-profile"),
                "about:blank"]
        self.log = open(os.path.join(workdir, "chromium.log"), "w")
        # The pipe's ends become fds 3 and 4 in Chromium (bash moves them there, then execs it).
        shell = 'exec "$@" 3<&%d 4>&%d %d<&- %d>&-' % (to_chrome_r, from_chrome_w, to_chrome_r, from_chrome_w)
        self.proc = subprocess.Popen(["bash", "-c", shell, "chromium"] + args, pass_fds=(to_chrome_r, from_chrome_w),
                                     stdout=self.log, stderr=subprocess.STDOUT)
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        self.buf = b""
        self.next_id = 1

    @staticmethod
    def _above_10(fd):
        high = fcntl.fcntl(fd, fcntl.F_DUPFD, 10)
        os.close(fd)
        return high

    def _read_message(self):
        while b"\0" not in self.buf:
            chunk = os.read(self.from_chrome, 1 << 16)
            if not chunk:
                fail("Chromium closed the DevTools pipe (see chromium.log)")
            self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method, params=None, session=None):
        mid = self.next_id
        self.next_id += 1
        msg = {"id": mid, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.to_chrome, json.dumps(msg).encode() + b"\0")
        while True:
            reply = self._read_message()
            if reply.get("id") == mid:
                if "error" in reply:
                    fail("%s: %s" % (method, reply["error"]))
                return reply["result"]

    def open_tab(self, url, width=1100, height=1400):
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        self.call("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}, session)
        self.call("Page.enable", {}, session)
        self.call("Page.navigate", {"url": url}, session)
        return session

    def eval(self, session, expression):
        r = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True, "awaitPromise": True},
                      session)
        if "exceptionDetails" in r:
            fail("page script failed: %s\n%s" % (expression, r["exceptionDetails"]))
        return r["result"].get("value")

    def screenshot(self, session, path):
        data = self.call("Page.captureScreenshot", {"format": "png", "captureBeyondViewport": False}, session)["data"]
        with open(path, "wb") as f:
            f.write(base64.b64decode(data))

    def close(self):
        try:
            self.call("Browser.close")
        except SystemExit:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


# What the test reads from the job page: the DOM's state badge, the preview's dataset and a digest of the
# preview's pixels (drawn on a canvas).
PAGE_STATE = r"""(async () => {
  // Not loaded yet until every element read below exists (the page's DOM can be caught half-built: "state"
  // there but not "b", which made this script throw instead of waiting).
  for (const id of ["state", "b", "cancel", "fetch-png", "error"])
    if (!document.getElementById(id)) return null;
  const img = document.getElementById("preview");
  let digest = null;
  if (img && img.complete && img.naturalWidth > 0) {
    const c = document.createElement("canvas");
    c.width = img.naturalWidth; c.height = img.naturalHeight;
    const g = c.getContext("2d");
    g.drawImage(img, 0, 0);
    const px = g.getImageData(0, 0, c.width, c.height).data;
    let h = 2166136261;
    for (let i = 0; i < px.length; ++i) { h ^= px[i]; h = Math.imul(h, 16777619) >>> 0; }
    digest = h;
  }
  return {state: document.getElementById("state").textContent, tasks: img ? img.dataset.tasks : null,
          final: img ? img.dataset.final : null, digest,
          b: document.getElementById("b").textContent,
          acceptanceRows: document.querySelectorAll("#acceptance tbody tr").length,
          cancelDisabled: document.getElementById("cancel").disabled,
          fetchDisabled: document.getElementById("fetch-png").disabled,
          error: document.getElementById("error").textContent};
})()"""


def wait_page(dt, session, pred, what):
    end = time.time() + TIMEOUT
    last = None
    while time.time() < end:
        last = dt.eval(session, PAGE_STATE)
        if last is not None and pred(last):
            return last
        time.sleep(0.1)
    fail("timed out waiting for %s; page: %s" % (what, last))


def read_line_with_prefix(proc, prefix):
    line = proc.stdout.readline().decode().strip()
    if not line.startswith(prefix):
        fail("expected '%s...' from the coordinator, got '%s'" % (prefix, line))
    return line[len(prefix):]


def api(port, path):
    req = urllib.request.Request("http://127.0.0.1:%d%s" % (port, path), headers={"Authorization": "Bearer " + TOKEN})
    with urllib.request.urlopen(req, timeout=10) as r:
        return json.loads(r.read())


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    tools, source, screenshot = sys.argv[1:4]
    chromium = find_chromium()
    if not chromium:
        print("SKIP: no Chromium installed (apt-get install chromium; deploy/setup.sh installs it)")
        return 77

    work = tempfile.mkdtemp(prefix="mltfarm-browser-")
    # The token reaches every program through the environment (argv is refused: others can read it).
    os.environ["MLTFARM_TOKEN"] = TOKEN
    procs = []
    dt = None
    ok = False
    try:
        coord = subprocess.Popen(
            [os.path.join(tools, "mltfarm-coordinator"), "--listen", "127.0.0.1:0", "--state-dir",
             os.path.join(work, "state"), "--http-listen", "127.0.0.1:0", "--heartbeat", "0.2",
             "--lease-timeout", "60"],
            stdout=subprocess.PIPE, stderr=open(os.path.join(work, "coordinator.log"), "w"))
        procs.append(coord)
        address = read_line_with_prefix(coord, "listening on ")
        http_port = int(read_line_with_prefix(coord, "http on ").rsplit(":", 1)[1])
        workers = []

        def start_workers():
            for i in range(2):
                workers.append(subprocess.Popen(
                    [os.path.join(tools, "mltfarm-worker"), "--coordinator", address, "--threads", "1",
                     "--cache-dir", os.path.join(work, "cache"), "--debug-task-delay-ms", "300"],
                    stdout=subprocess.DEVNULL, stderr=open(os.path.join(work, "worker-%d.log" % i), "w")))
                procs.append(workers[-1])

        def signal_workers(sig):
            for w in workers:
                w.send_signal(sig)

        def submit(name, priority):
            out = subprocess.run(
                [os.path.join(tools, "mltfarm"), "submit", os.path.join(source, "scenes", "cornell-box.xml"),
                 "--coordinator", address, "-m", "pssmlt", "--width", "160", "--height", "120",
                 "--mutations-per-pixel", "24", "--chains", "24", "--bootstrap", "20000", "--max-depth", "6",
                 "--seed", "7", "--name", name, "--priority", str(priority)],
                check=True, capture_output=True, text=True)
            return out.stdout.strip()

        job_a = submit("cornell box (pssmlt)", 0)
        job_b = submit("to be cancelled", -1)  # behind A: no task of B is leased while A has any queued
        # (no worker yet: nothing runs until the page is open)
        base = "http://127.0.0.1:%d" % http_port
        dt = DevTools(chromium, work)

        # The job list shows both jobs.
        index = dt.open_tab(base + "/#token=" + TOKEN)
        wait_page_list = time.time() + TIMEOUT
        while time.time() < wait_page_list:
            ids = dt.eval(index, "Array.from(document.querySelectorAll('#jobs tbody a')).map(a => a.textContent)")
            if ids and job_a in ids and job_b in ids:
                break
            time.sleep(0.1)
        else:
            fail("the job list never showed %s and %s" % (job_a, job_b))

        # Job A: the page is open before any worker runs. The workers start, and are paused (SIGSTOP) once
        # a task is accepted, so that the page's first preview is one of a job still running however slow
        # this machine is; B (behind A) cannot run meanwhile either.
        page = dt.open_tab(base + "/job.html?id=%s#token=%s" % (job_a, TOKEN))
        wait_page(dt, page, lambda s: s["state"] in ("QUEUED", "PLANNING", "RUNNING"), "A's page")
        start_workers()
        end = time.time() + TIMEOUT
        while api(http_port, "/api/jobs/" + job_a)["tasks_done"] < 1:
            if time.time() > end:
                fail("no task of %s accepted" % job_a)
            time.sleep(0.02)
        signal_workers(signal.SIGSTOP)
        if api(http_port, "/api/jobs/" + job_a)["state"] != "RUNNING":
            fail("%s finished before the workers were paused" % job_a)
        first = wait_page(dt, page, lambda s: s["digest"] is not None and s["final"] == "0", "A's first preview")
        print("first preview: %s tasks, pixels %08x" % (first["tasks"], first["digest"]))

        # Job B: cancelled with the page's button.
        other = dt.open_tab(base + "/job.html?id=%s#token=%s" % (job_b, TOKEN))
        before = wait_page(dt, other, lambda s: s["state"] not in ("…", "") and not s["cancelDisabled"], "B's page")
        if before["state"] in ("DONE", "FAILED", "CANCELLED"):
            fail("job B is already %s before the cancel" % before["state"])
        dt.eval(other, "document.getElementById('cancel').click(), true")
        wait_page(dt, other, lambda s: s["state"] == "CANCELLED" and s["cancelDisabled"], "B to show CANCELLED")
        if api(http_port, "/api/jobs/" + job_b)["state"] != "CANCELLED":
            fail("the API does not say %s is CANCELLED" % job_b)
        print("%s cancelled from the page" % job_b)

        # The workers go on: A's preview changes as more chains are accepted.
        signal_workers(signal.SIGCONT)
        changed = wait_page(dt, page, lambda s: s["digest"] is not None and s["digest"] != first["digest"]
                            and s["tasks"] != first["tasks"], "A's preview to change")
        print("changed preview: %s tasks, pixels %08x (final=%s)" % (changed["tasks"], changed["digest"], changed["final"]))
        if changed["final"] == "0" and int(changed["tasks"]) <= int(first["tasks"]):
            fail("the preview went back: %s then %s tasks" % (first["tasks"], changed["tasks"]))

        # Job A reaches DONE on its page with the finished image.
        done = wait_page(dt, page, lambda s: s["state"] == "DONE" and s["final"] == "1" and not s["fetchDisabled"],
                         "A to reach DONE with its final image")
        if done["acceptanceRows"] < 1 or "±" not in done["b"]:
            fail("the DONE page lacks b ± error or the acceptance table: %s" % done)
        if done["digest"] == first["digest"]:
            fail("the final image has the same pixels as the first preview")
        if done["error"]:
            fail("the page shows an error: " + done["error"])
        os.makedirs(os.path.dirname(os.path.abspath(screenshot)), exist_ok=True)
        dt.call("Emulation.setDeviceMetricsOverride",
                {"width": 1000, "height": 760, "deviceScaleFactor": 1, "mobile": False}, page)
        time.sleep(0.3)
        dt.screenshot(page, screenshot)
        with open(screenshot, "rb") as f:
            if f.read(8) != b"\x89PNG\r\n\x1a\n":
                fail("the screenshot is not a PNG")
        print("DONE on the page (b %s, %d acceptance rows); screenshot: %s" % (done["b"], done["acceptanceRows"], screenshot))
        ok = True
        return 0
    finally:
        if dt:
            dt.close()
        for p in reversed(procs):
            p.send_signal(signal.SIGCONT)  # a paused worker cannot act on SIGTERM
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=15)
            except subprocess.TimeoutExpired:
                p.kill()
        if ok:
            shutil.rmtree(work, ignore_errors=True)
        else:
            print("logs kept in " + work, file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
