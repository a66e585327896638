// GyroLab session page: charts, the position stepper, and the three ways of recording
// (typed grid, CSV file, simulated gyro over a WebSocket).  No inline scripts: the page's
// data arrive as JSON in <script type="application/json"> blocks.
(() => {
  "use strict";
  const config = JSON.parse(document.getElementById("lab-config").textContent);
  const figures = JSON.parse(document.getElementById("lab-figures").textContent);
  const t = (key, params = {}) =>
    (config.messages[key] || key).replace(/\{(\w+)\}/g, (_, name) => params[name] ?? "");
  const base = `/lab/sessions/${config.sessionId}`;
  const MAX_FILE_BYTES = 5_000_000;
  const LIVE_WINDOW = 600;
  const selected = { heading: 1, latitude: 1 };

  // --- charts -----------------------------------------------------------------------------
  const plotConfig = { responsive: true, displaylogo: false };
  document.querySelectorAll(".chart[data-figure]").forEach((element) => {
    const figure = figures[element.dataset.figure];
    if (figure && window.Plotly) Plotly.newPlot(element, figure.data, figure.layout, plotConfig);
  });

  async function postJson(path, body) {
    const response = await fetch(base + path, {
      method: "POST",
      headers: { "Content-Type": "application/json", "X-CSRF-Token": config.csrf },
      body: JSON.stringify(body),
    });
    let payload = {};
    try { payload = await response.json(); } catch (error) { payload = {}; }
    if (!response.ok) {
      const detail = typeof payload.detail === "string" ? payload.detail : t("js.failed");
      throw new Error(detail);
    }
    return payload;
  }

  function reloadSoon() { setTimeout(() => window.location.reload(), 400); }

  // --- stepper and method tabs ------------------------------------------------------------
  function selectPosition(part, position) {
    selected[part] = position;
    const section = document.getElementById(`part-${part}`);
    section.querySelectorAll(".step").forEach((step) => {
      step.setAttribute("aria-selected", String(Number(step.dataset.position) === position));
    });
    section.querySelectorAll(".axis").forEach((axis) => {
      axis.classList.toggle(
        "selected",
        Number(axis.dataset.position) === position || Number(axis.dataset.return) === position,
      );
    });
    updateTurnHint(part);
  }

  // The chosen tab and position survive the reload that follows each save.
  const memoryKey = `gyrolab-lab-${config.sessionId}`;
  const memory = JSON.parse(sessionStorage.getItem(memoryKey) || "{}");
  function remember(part, values) {
    memory[part] = { ...(memory[part] || {}), ...values };
    sessionStorage.setItem(memoryKey, JSON.stringify(memory));
  }

  document.querySelectorAll(".step").forEach((step) => {
    step.addEventListener("click", () => {
      selectPosition(step.dataset.part, Number(step.dataset.position));
      remember(step.dataset.part, { position: Number(step.dataset.position) });
    });
  });
  function showMethod(part, method) {
    const section = document.getElementById(`part-${part}`);
    const tab = section.querySelector(`.method-tab[data-method="${method}"]`);
    if (!tab) return;
    section.querySelectorAll(".method-tab").forEach((other) => other.classList.toggle("active", other === tab));
    section.querySelectorAll(".method-panel").forEach((panel) => {
      panel.hidden = panel.dataset.method !== method;
    });
  }
  document.querySelectorAll(".method-tab").forEach((tab) => {
    tab.addEventListener("click", () => {
      showMethod(tab.dataset.part, tab.dataset.method);
      remember(tab.dataset.part, { method: tab.dataset.method });
    });
  });

  // --- typed grid -------------------------------------------------------------------------
  function parseCell(text) {
    const value = text.trim();
    if (value === "") return { empty: true };
    if (!/^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(value)) return { error: "js.not_a_number" };
    const number = Number(value);
    if (!Number.isFinite(number)) return { error: "js.not_finite" };
    return { value: number };
  }

  function setupGrid(panel) {
    const body = panel.querySelector("tbody");
    const status = panel.querySelector(".grid-status");
    const columns = panel.querySelectorAll("thead th").length - 1;

    function addRows(count) {
      for (let i = 0; i < count; i += 1) {
        const row = document.createElement("tr");
        const label = document.createElement("th");
        label.textContent = String(body.rows.length + 1);
        row.appendChild(label);
        for (let c = 0; c < columns; c += 1) {
          const cell = document.createElement("td");
          const input = document.createElement("input");
          input.inputMode = "decimal";
          input.autocomplete = "off";
          input.dataset.column = String(c + 1);
          input.setAttribute("aria-label", `${t("js.position", { n: c + 1 })} #${body.rows.length + 1}`);
          cell.appendChild(input);
          row.appendChild(cell);
        }
        body.appendChild(row);
      }
    }

    function validate() {
      let problem = null;
      let count = 0;
      body.querySelectorAll("input").forEach((input) => {
        const parsed = parseCell(input.value);
        input.classList.toggle("invalid", Boolean(parsed.error));
        input.title = parsed.error ? t(parsed.error, { value: input.value }) : "";
        if (parsed.error && !problem) {
          problem = `${t("js.position", { n: input.dataset.column })}, #${input.closest("tr").rowIndex}: ${t(parsed.error, { value: input.value.trim() })}`;
        }
        if (parsed.value !== undefined) count += 1;
      });
      status.textContent = problem || (count ? t("js.grid_ok", { count }) : "");
      status.classList.toggle("error-text", Boolean(problem));
      return !problem;
    }

    body.addEventListener("input", validate);
    body.addEventListener("paste", (event) => {
      const target = event.target.closest("input");
      const text = (event.clipboardData || window.clipboardData).getData("text");
      if (!target || !/[\t\n,;]/.test(text.trim())) return;
      event.preventDefault();
      const lines = text.replace(/\r/g, "").split("\n").filter((line, i, all) => line.trim() !== "" || i < all.length - 1);
      const separator = text.includes("\t") ? "\t" : /[;]/.test(text) ? ";" : ",";
      const startRow = target.closest("tr").sectionRowIndex;
      const startColumn = Number(target.dataset.column) - 1;
      const needed = startRow + lines.length - body.rows.length;
      if (needed > 0) addRows(needed);
      lines.forEach((line, r) => {
        line.split(separator).forEach((value, c) => {
          const input = body.rows[startRow + r]?.querySelectorAll("input")[startColumn + c];
          if (input) input.value = value.trim();
        });
      });
      validate();
      status.textContent = `${t("js.pasted", { rows: lines.length })} ${status.textContent}`;
    });
    panel.querySelector(".add-rows").addEventListener("click", () => addRows(5));
    panel.querySelector(".clear-grid").addEventListener("click", () => {
      body.querySelectorAll("input").forEach((input) => { input.value = ""; });
      validate();
    });
    panel.querySelector(".save-manual").addEventListener("click", async () => {
      if (!validate()) return;
      const data = {};
      body.querySelectorAll("input").forEach((input) => {
        const parsed = parseCell(input.value);
        if (parsed.value === undefined) return;
        (data[input.dataset.column] ||= []).push(parsed.value);
      });
      if (!Object.keys(data).length) {
        status.textContent = t("js.grid_empty");
        status.classList.add("error-text");
        return;
      }
      status.textContent = t("js.saving");
      try {
        await postJson("/manual", { part: panel.dataset.part, unit: panel.querySelector(".unit").value, columns: data });
        status.textContent = t("js.saved");
        reloadSoon();
      } catch (error) {
        status.textContent = error.message;
        status.classList.add("error-text");
      }
    });
    addRows(Math.max(10, config.minReadings));
  }
  document.querySelectorAll('.method-panel[data-method="manual"]').forEach(setupGrid);

  // --- CSV file ---------------------------------------------------------------------------
  function setupCsv(panel) {
    const input = panel.querySelector(".csv-file");
    const preview = panel.querySelector(".csv-preview");
    const accept = panel.querySelector(".accept-csv");
    let text = null;

    async function showPreview() {
      accept.disabled = true;
      preview.textContent = "";
      const file = input.files[0];
      if (!file) return;
      if (file.size > MAX_FILE_BYTES) {
        preview.innerHTML = `<p class="error-text">${t("js.too_large")}</p>`;
        return;
      }
      text = await file.text();
      try {
        const result = await postJson("/csv/preview", { part: panel.dataset.part, unit: panel.querySelector(".unit").value, text });
        const rows = result.positions.map((p) =>
          `<tr><td>${p.position}</td><td class="num">${p.angle_deg}°</td><td class="num">${p.n}</td><td class="num">${p.mean_deg_h.toFixed(3)}</td><td>${p.first.map((v) => v.toFixed(3)).join(", ")}…</td></tr>`).join("");
        preview.innerHTML = `<p>${t("js.preview_title")}</p><table class="table compact"><thead><tr><th>#</th><th class="num">${t("js.angle")}</th><th class="num">n</th><th class="num">${t("js.mean")}</th><th>${t("js.samples")}</th></tr></thead><tbody>${rows}</tbody></table>`;
        accept.disabled = false;
      } catch (error) {
        const message = document.createElement("p");
        message.className = "error-text";
        message.textContent = error.message;
        preview.replaceChildren(message);
      }
    }
    input.addEventListener("change", showPreview);
    panel.querySelector(".unit").addEventListener("change", showPreview);
    accept.addEventListener("click", async () => {
      accept.disabled = true;
      try {
        await postJson("/csv", { part: panel.dataset.part, unit: panel.querySelector(".unit").value, text });
        preview.textContent = t("js.saved");
        reloadSoon();
      } catch (error) {
        preview.textContent = error.message;
        accept.disabled = false;
      }
    });
  }
  document.querySelectorAll('.method-panel[data-method="csv"]').forEach(setupCsv);

  // --- simulated gyro ---------------------------------------------------------------------
  function updateTurnHint(part) {
    const panel = document.querySelector(`.method-panel[data-method="simulator"][data-part="${part}"]`);
    if (!panel) return;
    panel.querySelector(".table-position").textContent = String(config.table[part]);
    const ready = config.table[part] === selected[part];
    panel.querySelector(".turn").disabled = ready;
    panel.querySelector(".start-sim").disabled = !ready || panel.dataset.busy === "1";
    panel.querySelector(".sim-status").textContent = ready ? "" : t("js.turn_needed", { n: selected[part] });
  }

  function setupSimulator(panel) {
    const part = panel.dataset.part;
    const status = panel.querySelector(".sim-status");
    const progress = panel.querySelector(".sim-progress");
    const startButton = panel.querySelector(".start-sim");
    const stopButton = panel.querySelector(".stop-sim");
    const chart = panel.querySelector(".live-chart");
    let socket = null;
    let saved = false;

    panel.querySelector(".turn").addEventListener("click", async () => {
      try {
        await postJson("/turn", { part, position: selected[part] });
        config.table[part] = selected[part];
        updateTurnHint(part);
        status.textContent = t("js.turned", { n: selected[part] });
      } catch (error) {
        status.textContent = error.message;
      }
    });

    const planeButton = panel.querySelector(".set-plane");
    if (planeButton) {
      planeButton.addEventListener("click", async () => {
        const planeStatus = panel.querySelector(".plane-status");
        const value = Number(panel.querySelector(".plane-dial").value);
        if (panel.querySelector(".plane-dial").value.trim() === "" || !Number.isFinite(value)) {
          planeStatus.textContent = t("js.not_a_number");
          return;
        }
        try {
          const reply = await postJson("/plane", { dial_deg: value });
          planeStatus.textContent = t("js.plane_set", { dial: reply.dial_deg });
        } catch (error) {
          planeStatus.textContent = error.message;
        }
      });
    }

    function finish(message) {
      panel.dataset.busy = "0";
      stopButton.disabled = true;
      updateTurnHint(part);
      if (message) status.textContent = message;
    }

    startButton.addEventListener("click", () => {
      const scheme = window.location.protocol === "https:" ? "wss" : "ws";
      socket = new WebSocket(`${scheme}://${window.location.host}${base}/stream`);
      saved = false;
      panel.dataset.busy = "1";
      startButton.disabled = true;
      socket.addEventListener("open", () => {
        socket.send(JSON.stringify({
          action: "start", part, position: selected[part],
          dwell_s: Number(panel.querySelector(".dwell").value),
          settle_s: Number(panel.querySelector(".settle").value),
          speed: Number(panel.querySelector(".speed").value),
        }));
      });
      socket.addEventListener("message", (event) => {
        const frame = JSON.parse(event.data);
        if (frame.type === "started") {
          progress.max = frame.total;
          progress.value = 0;
          stopButton.disabled = false;
          status.textContent = t("js.recording", { n: frame.position });
          Plotly.newPlot(chart, [{ x: [], y: [], mode: "lines", type: "scatter", line: { width: 1 } }], {
            margin: { l: 60, r: 10, t: 10, b: 40 }, height: 220,
            xaxis: { title: { text: t("chart.time_s") } }, yaxis: { title: { text: t("chart.rate_deg_h") } },
          }, plotConfig);
        } else if (frame.type === "samples") {
          Plotly.extendTraces(chart, { x: [frame.t], y: [frame.v] }, [0], LIVE_WINDOW);
          progress.value = frame.done;
        } else if (frame.type === "saved") {
          saved = true;
          remember(part, { position: Math.min(frame.position + 1, 4) });
          finish(t("js.done", { n: frame.n }));
          socket.close();
          reloadSoon();
        } else if (frame.type === "error") {
          finish(frame.message);
          socket.close();
        }
      });
      socket.addEventListener("close", () => {
        if (!saved && panel.dataset.busy === "1") finish(t("js.connection_lost"));
      });
    });
    stopButton.addEventListener("click", () => {
      if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify({ action: "stop" }));
      stopButton.disabled = true;
    });
  }
  document.querySelectorAll('.method-panel[data-method="simulator"]').forEach(setupSimulator);

  ["heading", "latitude"].forEach((part) => {
    if (!document.getElementById(`part-${part}`)) return;
    selectPosition(part, memory[part]?.position || 1);
    if (memory[part]?.method) showMethod(part, memory[part].method);
  });
})();
