// Error-analysis explorer: every change of a control asks the server for new curves
// (debounced) and redraws the charts (static/js/charts.js draws each once it is in view).
(() => {
  "use strict";
  const config = JSON.parse(document.getElementById("explorer-config").textContent);
  const t = (key, params = {}) =>
    (config.messages[key] || key).replace(/\{(\w+)\}/g, (_, name) => params[name] ?? "");
  const form = document.getElementById("explorer-form");
  const info = document.getElementById("run-info");
  const colors = { two: "#D55E00", four: "#0072B2", seeker: "#009E73" };  // Okabe–Ito, as the lab's charts
  // at the foot of the whole figure, never on the x axis's title (as the lab's charts)
  const LEGEND = { orientation: "h", x: 0, xanchor: "left", y: 0, yref: "container", yanchor: "bottom" };
  let timer = null;
  let generation = 0;
  const round = (value, digits = 3) => (value === null || !Number.isFinite(value) ? "—" : Number(value.toFixed(digits)).toString());

  // Each chart's text alternative: a sentence under it and its numbers in a table.
  function describe(chartId, sentence, columns, rows) {
    document.getElementById(`${chartId}-summary`).textContent = sentence;
    const table = document.getElementById(`${chartId}-table`);
    table.replaceChildren();
    const head = table.createTHead().insertRow();
    columns.forEach((name) => { const th = document.createElement("th"); th.scope = "col"; th.textContent = name; head.appendChild(th); });
    const body = table.createTBody();
    rows.forEach((cells) => { const row = body.insertRow(); cells.forEach((cell) => { row.insertCell().textContent = cell; }); });
  }

  function largest(xs, ys) {
    let best = 0;
    ys.forEach((y, i) => { if (Number.isFinite(y) && Math.abs(y) > Math.abs(ys[best] ?? 0)) best = i; });
    return { x: xs[best], y: ys[best] };
  }

  function describeAll(data) {
    const names = data.curves.map((curve) => t(`explore.method_${curve.method}`));
    describe("heading-chart",
      data.curves.map((curve, i) => { const top = largest(curve.azimuths_deg, curve.formula_deg);
        return t("explore.summary_heading", { method: names[i], error: round(top.y), azimuth: round(top.x, 1) }); }).join(" "),
      [t("explore.axis_azimuth"), ...names.map((name) => `${name} — ${t("explore.formula")}`)],
      (data.curves[0]?.azimuths_deg || []).map((azimuth, row) => [round(azimuth, 1), ...data.curves.map((curve) => round(curve.formula_deg[row]))]));
    const dwell = data.dwell;
    const last = dwell.dwell_s.length - 1;
    describe("dwell-chart",
      t("explore.summary_dwell", { first: round(dwell.sigma_deg[0]), from: round(dwell.dwell_s[0], 1), last: round(dwell.sigma_deg[last]), to: round(dwell.dwell_s[last], 1), floor: round(dwell.floor_deg) }) + " " + (dwell.advice || []).join(" "),
      [t("explore.dwell_axis"), t("explore.expected"), t("explore.white_only")],
      dwell.dwell_s.map((seconds, i) => [round(seconds, 1), round(dwell.sigma_deg[i], 4), round(dwell.white_only_deg[i], 4)]));
    const orders = Object.entries(data.orders.orders);
    describe("order-chart",
      orders.map(([order, errors]) => { const top = largest(data.orders.azimuth_deg, errors);
        return t("explore.summary_orders", { order: t(`explore.order_${order}`), error: round(top.y), azimuth: round(top.x, 1) }); }).join(" "),
      [t("explore.axis_azimuth"), ...orders.map(([order]) => t(`explore.order_${order}`))],
      data.orders.azimuth_deg.map((azimuth, row) => [round(azimuth, 1), ...orders.map(([, errors]) => round(errors[row]))]));
  }

  function showOutputs() {
    form.querySelectorAll("output").forEach((output) => {
      const input = document.getElementById(output.htmlFor.value || output.getAttribute("for"));
      if (input) output.textContent = `${input.value}${output.dataset.unit}`;
    });
  }

  function query() {
    const params = new URLSearchParams();
    for (const element of form.elements) {
      if (!element.name || element.name === "scenario") continue;
      if (element.type === "radio" && !element.checked) continue;
      if (element.type === "checkbox") { params.set(element.name, element.checked ? "true" : "false"); continue; }
      params.set(element.name, element.value);
    }
    return params;
  }

  async function update() {
    showOutputs();
    const params = query();
    document.getElementById("csv-heading").href = `/explore/data.csv?chart=heading&${params}`;
    document.getElementById("csv-dwell").href = `/explore/data.csv?chart=dwell&${params}`;
    document.getElementById("csv-orders").href = `/explore/data.csv?chart=orders&${params}`;
    const mine = ++generation;
    const response = await fetch(`/explore/data?${params}`, { headers: { Accept: "application/json" } });
    if (mine !== generation) return;  // a newer request is on its way
    if (!response.ok) { info.textContent = `${response.status}`; return; }
    const data = await response.json();
    describeAll(data);
    const traces = [];
    data.curves.forEach((curve) => {
      const name = t(`explore.method_${curve.method}`);
      traces.push({ x: curve.azimuths_deg, y: curve.formula_deg, mode: "lines", name: `${name} — ${t("explore.formula")}`,
                    line: { color: colors[curve.method], width: 2 } });
      traces.push({ x: curve.mc_azimuths_deg, y: curve.mc_mean_deg, mode: "markers", name: `${name} — ${t("explore.monte_carlo")}`,
                    marker: { color: colors[curve.method], size: 8, symbol: { two: "circle", four: "diamond", seeker: "square" }[curve.method] },
                    error_y: { type: "data", array: curve.mc_std_deg, visible: true } });
    });
    GyroCharts.show("heading-chart", { data: traces, layout: {
      title: { text: t("explore.chart_title") }, height: 420, margin: { l: 60, r: 20, t: 50, b: 60 },
      xaxis: { title: { text: t("explore.axis_azimuth") }, range: [0, 360], dtick: 45, automargin: true },
      yaxis: { title: { text: t("explore.axis_error") }, zeroline: true, automargin: true },
      legend: LEGEND,
    }});
    info.textContent = t("explore.runs_used", { runs: data.info.runs, points: data.info.points,
                                                 total: data.info.simulated_runs, seconds: data.info.seconds });
    const dwell = data.dwell;
    const floor = dwell.dwell_s.map(() => dwell.floor_deg);
    GyroCharts.show("dwell-chart", { data: [
      { x: dwell.dwell_s, y: dwell.sigma_deg, mode: "lines", name: t("explore.expected"), line: { width: 3, color: "#0072B2" } },
      { x: dwell.dwell_s, y: dwell.white_only_deg, mode: "lines", name: t("explore.white_only"), line: { dash: "dot", color: "#5d6b7a" } },
      { x: dwell.dwell_s, y: floor, mode: "lines", name: t("explore.floor"), line: { dash: "dash", color: "#D55E00" } },
    ], layout: {
      title: { text: t("explore.dwell_title") }, height: 340, margin: { l: 60, r: 20, t: 50, b: 60 },
      xaxis: { type: "log", title: { text: t("explore.dwell_axis") }, automargin: true },
      yaxis: { type: "log", title: { text: t("explore.sigma_axis") }, automargin: true },
      legend: LEGEND,
      shapes: dwell.knee_s ? [{ type: "line", x0: dwell.knee_s, x1: dwell.knee_s, yref: "paper", y0: 0, y1: 1, line: { color: "#E69F00", dash: "dot" } }] : [],
    }});
    const orderColors = { "1234": "#D55E00", "1324": "#E69F00", "12344321": "#0072B2" };
    GyroCharts.show("order-chart", { data: Object.entries(data.orders.orders).map(([order, errors]) => ({
      x: data.orders.azimuth_deg, y: errors, mode: "lines", name: t(`explore.order_${order}`),
      line: { color: orderColors[order], width: order === "12344321" ? 3 : 2, dash: order === "1324" ? "dash" : "solid" },
    })), layout: {
      title: { text: t("explore.orders_title") }, height: 340, margin: { l: 60, r: 20, t: 50, b: 60 },
      xaxis: { title: { text: t("explore.axis_azimuth") }, range: [0, 360], dtick: 45, automargin: true },
      yaxis: { title: { text: t("explore.axis_error") }, zeroline: true, automargin: true },
      legend: LEGEND,
    }});
  }

  function schedule() {
    clearTimeout(timer);
    timer = setTimeout(update, 150);
  }

  function applyScenario(name) {
    const values = { ...config.defaults, ...(config.scenarios[name] || {}) };
    for (const element of form.elements) {
      if (!element.name || !(element.name in values)) continue;
      if (element.type === "radio") element.checked = element.value === values[element.name];
      else if (element.type === "checkbox") element.checked = Boolean(values[element.name]);
      else element.value = values[element.name];
    }
    document.getElementById("scenario-text").textContent = config.texts[name] || "";
  }

  form.addEventListener("input", (event) => {
    if (event.target.name === "scenario") {
      applyScenario(event.target.value);
    } else if (event.target.name !== "scenario") {
      document.getElementById("scenario").value = document.getElementById("scenario").value;
    }
    schedule();
  });
  form.addEventListener("submit", (event) => event.preventDefault());
  update();
})();
