// Charts drawn only when they come into view, with plotly.js (1.4 MB compressed) fetched
// the first time one does: a page opens and works before plotly arrives, and a page whose
// charts are never scrolled to never fetches it.  The toolbar speaks the page's language
// (the words in #plotly-locale are ours, from the catalogue).
(() => {
  "use strict";
  const script = document.currentScript;
  const source = script.dataset.plotly;
  const failedText = script.dataset.failed || "";
  const options = {
    responsive: true,
    displaylogo: false,
    modeBarButtonsToRemove: ["select2d", "lasso2d", "autoScale2d", "toggleSpikelines", "hoverClosestCartesian", "hoverCompareCartesian"],
  };
  let loading = null;

  function registerLocale() {
    const block = document.getElementById("plotly-locale");
    const name = document.documentElement.lang || "en";
    if (!block || name.startsWith("en")) return; // plotly's own words are English
    Plotly.register({ moduleType: "locale", name, dictionary: JSON.parse(block.textContent), format: {} });
    Plotly.setPlotConfig({ locale: name });
  }

  // plotly itself, fetched once (a failed fetch is tried again by the next chart)
  function plotly() {
    if (window.Plotly) return Promise.resolve(window.Plotly);
    if (!loading) {
      loading = new Promise((resolve, reject) => {
        const tag = document.createElement("script");
        tag.src = source;
        tag.addEventListener("load", () => { registerLocale(); resolve(window.Plotly); });
        tag.addEventListener("error", () => { loading = null; tag.remove(); reject(new Error("plotly")); });
        document.head.append(tag);
      });
    }
    return loading;
  }

  // the newest figure asked for each chart not yet drawn, and the charts drawn
  const latest = new Map();
  const drawn = new WeakSet();
  const observer = "IntersectionObserver" in window
    ? new IntersectionObserver((entries) => {
      entries.forEach((entry) => {
        if (!entry.isIntersecting) return;
        observer.unobserve(entry.target);
        render(entry.target);
      });
    }, { rootMargin: "400px 0px" })
    : null;

  function render(element) {
    plotly().then((P) => {
      const figure = latest.get(element);
      if (!figure) return;
      latest.delete(element);
      drawn.add(element);
      element.removeAttribute("data-chart-failed");
      return P.react(element, figure.data, figure.layout, options);
    }).catch(() => {
      // the chart's sentence and data table beside it still carry its numbers
      element.dataset.chartFailed = "1";
      element.textContent = failedText;
    });
  }

  // Draw (or redraw) a chart: at once if it was drawn before, else when it comes into view.
  function show(element, figure) {
    if (typeof element === "string") element = document.getElementById(element);
    if (!element) return;
    const waiting = latest.has(element);
    latest.set(element, figure);
    if (drawn.has(element) || !observer) render(element);
    else if (!waiting) observer.observe(element);
  }

  // Every `.chart[data-figure]` of the page from a {name: figure} map.
  function showAll(figures) {
    document.querySelectorAll(".chart[data-figure]").forEach((element) => {
      const figure = figures[element.dataset.figure];
      if (figure) show(element, figure);
    });
  }

  window.GyroCharts = { plotly, show, showAll, options };
})();
