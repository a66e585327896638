// The class board: draws its charts, and while it is live (not a snapshot) asks the server
// every 10 s for the class's newest results and redraws the charts and the pooled numbers.
(() => {
  "use strict";
  const board = document.getElementById("class-board");
  const figures = JSON.parse(document.getElementById("lab-figures").textContent);
  GyroCharts.showAll(figures);
  const live = board && board.dataset.live;
  if (!live) return;
  let count = document.querySelectorAll("#board-table tbody tr").length;
  async function refresh() {
    try {
      const response = await fetch(live, { headers: { Accept: "application/json" } });
      if (!response.ok) return;
      const data = await response.json();
      // a new group, or a group without a chart yet: the page itself has the new layout
      if (data.board.groups.length !== count || document.querySelectorAll(".chart[data-figure]").length !== Object.keys(data.figures).length) {
        count = data.board.groups.length;
        window.location.reload();
        return;
      }
      document.querySelectorAll(".chart[data-figure]").forEach((element) => {
        const figure = data.figures[element.dataset.figure];
        if (figure) GyroCharts.show(element, figure);
      });
    } catch (error) {
      // offline for a moment: the next round tries again
    }
  }
  setInterval(refresh, 10_000);
})();
