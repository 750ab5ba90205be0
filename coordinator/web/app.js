// mltfarm coordinator page: plain JavaScript, no build step. Polls the JSON API (coordinator/http_server.h)
// once a second; the job page reloads the preview image whenever more tasks are accepted.
// The token (if the coordinator has one) comes from the URL fragment (#token=...) or the form, and is
// kept in this tab's sessionStorage; it is sent as "Authorization: Bearer ...", never in a URL.
"use strict";
const mltfarm = (() => {
  const $ = (id) => document.getElementById(id);
  const POLL_MS = 1000;

  function takeTokenFromFragment() {
    const m = location.hash.match(/token=([^&]*)/);
    if (m) {
      sessionStorage.setItem("mltfarm-token", decodeURIComponent(m[1]));
      history.replaceState(null, "", location.pathname + location.search);
    }
  }

  function showLogin(retry) {
    const box = $("login");
    box.hidden = false;
    box.querySelector("form").onsubmit = (e) => {
      e.preventDefault();
      sessionStorage.setItem("mltfarm-token", box.querySelector("input").value);
      box.hidden = true;
      retry();
    };
  }

  class Unauthorized extends Error {}

  async function api(path, options = {}) {
    const headers = {};
    const token = sessionStorage.getItem("mltfarm-token");
    if (token) headers["Authorization"] = "Bearer " + token;
    const res = await fetch(path, { ...options, headers });
    if (res.status === 401) throw new Unauthorized("token needed");
    if (!res.ok) {
      let message = res.status + " " + res.statusText;
      try { message = (await res.json()).error || message; } catch (_) { /* not JSON */ }
      const err = new Error(message);
      err.status = res.status;
      throw err;
    }
    return res;
  }

  function fmtSeconds(s) {
    if (s === null || s === undefined || s < 0) return "–";
    if (s < 60) return s.toFixed(s < 10 ? 1 : 0) + " s";
    if (s < 3600) return Math.floor(s / 60) + " min " + Math.round(s % 60) + " s";
    return Math.floor(s / 3600) + " h " + Math.round((s % 3600) / 60) + " min";
  }
  const fmtNum = (x, digits = 4) => (x === null || x === undefined ? "–" : Number(x).toPrecision(digits));
  const pct = (x) => (100 * x).toFixed(1) + "%";
  const terminal = (state) => state === "DONE" || state === "FAILED" || state === "CANCELLED";

  function cell(text, cls) {
    const td = document.createElement("td");
    if (cls) td.className = cls;
    if (text instanceof Node) td.appendChild(text);
    else td.textContent = text;
    return td;
  }
  function stateBadge(state) {
    const s = document.createElement("span");
    s.className = "state " + state;
    s.textContent = state;
    return s;
  }
  function progressBar(p) {
    const bar = document.createElement("div");
    bar.className = "bar";
    const fill = document.createElement("span");
    fill.style.width = pct(p);
    bar.appendChild(fill);
    return bar;
  }
  function fillRows(tbody, rows) {
    tbody.replaceChildren(...rows.map((cells) => {
      const tr = document.createElement("tr");
      cells.forEach((c) => tr.appendChild(c));
      return tr;
    }));
  }

  // A loop that polls `step` every POLL_MS and reports errors; asks for the token on 401.
  function poll(step) {
    let timer = null;
    const run = async () => {
      clearTimeout(timer);
      try {
        const again = await step();
        $("error").textContent = "";
        if (again === false) return;
      } catch (e) {
        if (e instanceof Unauthorized) return showLogin(run);
        $("error").textContent = e.message;
      }
      timer = setTimeout(run, POLL_MS);
    };
    takeTokenFromFragment();
    run();
    return run;
  }

  function startJobList() {
    poll(async () => {
      const { jobs } = await (await api("/api/jobs")).json();
      $("empty").hidden = jobs.length > 0;
      fillRows($("jobs").tBodies[0], jobs.slice().reverse().map((j) => {
        const a = document.createElement("a");
        a.href = "/job.html?id=" + encodeURIComponent(j.id);
        a.textContent = j.id;
        return [cell(a), cell(j.name), cell(j.method), cell(stateBadge(j.state)), cell(progressBar(j.progress)),
                cell(j.tasks_done + "/" + j.tasks_total, "num"), cell(fmtSeconds(j.eta_seconds), "num")];
      }));
      const { workers } = await (await api("/api/workers")).json();
      fillRows($("workers").tBodies[0], workers.map((w) => [cell(w.id), cell(w.host), cell(String(w.threads), "num"),
        cell(w.tasks.map((t) => t.job + "#" + t.task).join(", ") || "idle")]));
    });
  }

  async function download(path, filename) {
    const blob = await (await api(path)).blob();
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = filename;
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  }

  function startJobPage(id) {
    if (!id) {
      $("error").textContent = "no job id in the address (job.html?id=job-N)";
      return;
    }
    document.title = "mltfarm — " + id;
    $("title").textContent = id;
    const base = "/api/jobs/" + encodeURIComponent(id);
    const img = $("preview");
    let shown = null;  // "tasks/final" of the image on screen
    let refresh = null;

    async function loadPreview(job) {
      const want = job.tasks_done + "/" + (job.state === "DONE" ? 1 : 0);
      if (job.tasks_done === 0 || want === shown) return;
      let res;
      try {
        res = await api(base + "/preview.png");
      } catch (e) {
        if (e.status === 409) return;  // nothing accepted yet, or the job stopped without an image
        throw e;
      }
      const blob = await res.blob();
      const old = img.src;
      img.src = URL.createObjectURL(blob);
      if (old) URL.revokeObjectURL(old);
      img.dataset.tasks = res.headers.get("X-Preview-Tasks");
      img.dataset.final = res.headers.get("X-Preview-Final");
      img.dataset.loads = String(Number(img.dataset.loads) + 1);
      shown = want;
      $("preview-note").textContent = img.dataset.final === "1"
        ? "The finished image."
        : "Developed from the " + img.dataset.tasks + " of " + job.tasks_total + " tasks accepted so far (exact for those).";
    }

    function show(job) {
      $("name").textContent = job.name || job.id;
      const badge = $("state");
      badge.className = "state " + job.state;
      badge.textContent = job.state;
      $("method").textContent = job.method + " · " + job.width + "×" + job.height;
      $("bar").style.width = pct(job.progress);
      $("progress").textContent = pct(job.progress) + " · " + job.phase;
      $("tasks").textContent = job.tasks_done + " done, " + job.tasks_leased + " leased, " + job.tasks_queued +
        " queued of " + job.tasks_total;
      $("eta").textContent = fmtSeconds(job.eta_seconds);
      $("elapsed").textContent = fmtSeconds(job.elapsed_seconds);
      $("b").textContent = job.b ? fmtNum(job.b) + " ± " + fmtNum(job.b_stderr, 2) +
        " (" + pct(job.b_relative_stderr) + ")" : "–";
      $("bootstrap").textContent = job.bootstrap_seconds ? fmtSeconds(job.bootstrap_seconds) : "–";
      $("rate").textContent = job.samples_per_second ? fmtNum(job.samples_per_second, 3) + " samples/s" :
        job.samples + " samples";
      $("failures").textContent = String(job.failed_attempts);
      $("job-error").textContent = job.error;
      $("cancel").disabled = terminal(job.state);
      $("fetch-png").disabled = $("fetch-exr").disabled = job.state !== "DONE";
      $("acceptance-none").hidden = job.acceptance.length > 0;
      fillRows($("acceptance").tBodies[0], job.acceptance.map((a) => [cell(String(a.path_length)),
        cell(String(a.proposed), "num"), cell(String(a.accepted), "num"), cell(pct(a.ratio), "num")]));
      fillRows($("workers").tBodies[0], job.workers.map((w) => [cell(w.id), cell(w.host),
        cell(w.tasks.map((t) => "#" + t.task).join(", "))]));
    }

    $("cancel").onclick = async () => {
      $("cancel").disabled = true;
      try {
        await api(base + "/cancel", { method: "POST" });
      } catch (e) {
        $("error").textContent = e.message;
      }
      refresh();
    };
    $("fetch-png").onclick = () => download(base + "/result.png", id + ".png").catch((e) => ($("error").textContent = e.message));
    $("fetch-exr").onclick = () => download(base + "/result.exr", id + ".exr").catch((e) => ($("error").textContent = e.message));

    refresh = poll(async () => {
      const job = await (await api(base)).json();
      show(job);
      await loadPreview(job);
      return !(terminal(job.state) && (job.state !== "DONE" || shown === job.tasks_done + "/1"));
    });
  }

  return { startJobList, startJobPage };
})();
