// Error-analysis explorer: every change of a control asks the server for new curves
// (debounced) and redraws both charts with Plotly.react.
(() => {
  "use strict";
  const config = JSON.parse(document.getElementById("explorer-config").textContent);
  const t = (key, params = {}) =>
    (config.messages[key] || key).replace(/\{(\w+)\}/g, (_, name) => params[name] ?? "");
  const form = document.getElementById("explorer-form");
  const info = document.getElementById("run-info");
  const colors = { two: "#d1495b", four: "#0b6bcb", seeker: "#2a9d4b" };
  let timer = null;
  let generation = 0;

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
    const traces = [];
    data.curves.forEach((curve) => {
      const name = t(`explore.method_${curve.method}`);
      traces.push({ x: curve.azimuths_deg, y: curve.formula_deg, mode: "lines", name: `${name} — ${t("explore.formula")}`,
                    line: { color: colors[curve.method], width: 2 } });
      traces.push({ x: curve.mc_azimuths_deg, y: curve.mc_mean_deg, mode: "markers", name: `${name} — ${t("explore.monte_carlo")}`,
                    marker: { color: colors[curve.method], size: 8, symbol: { two: "circle", four: "diamond", seeker: "square" }[curve.method] },
                    error_y: { type: "data", array: curve.mc_std_deg, visible: true } });
    });
    Plotly.react("heading-chart", traces, {
      title: { text: t("explore.chart_title") }, height: 420, margin: { l: 60, r: 20, t: 50, b: 60 },
      xaxis: { title: { text: t("explore.axis_azimuth") }, range: [0, 360], dtick: 45 },
      yaxis: { title: { text: t("explore.axis_error") }, zeroline: true },
      legend: { orientation: "h", y: -0.2 },
    }, { responsive: true, displaylogo: false, modeBarButtonsToRemove: ["select2d", "lasso2d", "autoScale2d", "toggleSpikelines", "hoverClosestCartesian", "hoverCompareCartesian"] });
    info.textContent = t("explore.runs_used", { runs: data.info.runs, points: data.info.points,
                                                 total: data.info.simulated_runs, seconds: data.info.seconds });
    const dwell = data.dwell;
    const floor = dwell.dwell_s.map(() => dwell.floor_deg);
    Plotly.react("dwell-chart", [
      { x: dwell.dwell_s, y: dwell.sigma_deg, mode: "lines", name: t("explore.expected"), line: { width: 3, color: "#0b6bcb" } },
      { x: dwell.dwell_s, y: dwell.white_only_deg, mode: "lines", name: t("explore.white_only"), line: { dash: "dot", color: "#5d6b7a" } },
      { x: dwell.dwell_s, y: floor, mode: "lines", name: t("explore.floor"), line: { dash: "dash", color: "#d1495b" } },
    ], {
      title: { text: t("explore.dwell_title") }, height: 340, margin: { l: 60, r: 20, t: 50, b: 60 },
      xaxis: { type: "log", title: { text: t("explore.dwell_axis") } },
      yaxis: { type: "log", title: { text: t("explore.sigma_axis") } },
      legend: { orientation: "h", y: -0.3 },
      shapes: dwell.knee_s ? [{ type: "line", x0: dwell.knee_s, x1: dwell.knee_s, yref: "paper", y0: 0, y1: 1, line: { color: "#e9a23b", dash: "dot" } }] : [],
    }, { responsive: true, displaylogo: false, modeBarButtonsToRemove: ["select2d", "lasso2d", "autoScale2d", "toggleSpikelines", "hoverClosestCartesian", "hoverCompareCartesian"] });
    const orderColors = { "1234": "#d1495b", "1324": "#e9a23b", "12344321": "#0b6bcb" };
    Plotly.react("order-chart", Object.entries(data.orders.orders).map(([order, errors]) => ({
      x: data.orders.azimuth_deg, y: errors, mode: "lines", name: t(`explore.order_${order}`),
      line: { color: orderColors[order], width: order === "12344321" ? 3 : 2 },
    })), {
      title: { text: t("explore.orders_title") }, height: 340, margin: { l: 60, r: 20, t: 50, b: 60 },
      xaxis: { title: { text: t("explore.axis_azimuth") }, range: [0, 360], dtick: 45 },
      yaxis: { title: { text: t("explore.axis_error") }, zeroline: true },
      legend: { orientation: "h", y: -0.3 },
    }, { responsive: true, displaylogo: false, modeBarButtonsToRemove: ["select2d", "lasso2d", "autoScale2d", "toggleSpikelines", "hoverClosestCartesian", "hoverCompareCartesian"] });
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
