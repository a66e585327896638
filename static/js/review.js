// Teacher pages: draw the server-built plotly figures and sort the class table by column.
(() => {
  "use strict";
  const figures = {};
  ["lab-figures", "evidence-figures"].forEach((id) => {
    const data = document.getElementById(id);
    if (data) Object.assign(figures, JSON.parse(data.textContent));
  });
  GyroCharts.showAll(figures);

  document.querySelectorAll("table.sortable").forEach((table) => {
    table.querySelectorAll("th[data-sort]").forEach((header, column) => {
      header.tabIndex = 0;
      header.classList.add("sort-header");
      const sort = () => {
        const ascending = header.getAttribute("aria-sort") !== "ascending";
        table.querySelectorAll("th[aria-sort]").forEach((other) => other.removeAttribute("aria-sort"));
        header.setAttribute("aria-sort", ascending ? "ascending" : "descending");
        const key = (row) => {
          const cell = row.cells[column];
          const raw = cell.dataset.value ?? cell.textContent.trim();
          if (header.dataset.sort === "num") return raw === "" ? Infinity : Number(raw);
          return raw.toLowerCase();
        };
        const rows = [...table.tBodies[0].rows];
        rows.sort((a, b) => {
          const x = key(a);
          const y = key(b);
          const order = x < y ? -1 : x > y ? 1 : 0;
          return ascending ? order : -order;
        });
        rows.forEach((row) => table.tBodies[0].appendChild(row));
      };
      header.addEventListener("click", sort);
      header.addEventListener("keydown", (event) => { if (event.key === "Enter") sort(); });
    });
  });
})();
