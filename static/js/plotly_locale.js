// Plotly's chart toolbar in the page's language: the page's own words (#plotly-locale)
// registered as a plotly locale and made every chart's default.
(() => {
  "use strict";
  const block = document.getElementById("plotly-locale");
  if (!window.Plotly || !block) return;
  const name = document.documentElement.lang || "en";
  if (name.startsWith("en")) return; // plotly's own words are English
  Plotly.register({ moduleType: "locale", name, dictionary: JSON.parse(block.textContent), format: {} });
  Plotly.setPlotConfig({ locale: name });
})();
