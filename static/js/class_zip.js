// The class's reports zip (templates/reports/class_zip.html): while it is being built,
// ask for its progress every two seconds; when it is done, show the download (the page's
// text comes back from the server, in the page's language, on the reload).
(function () {
  "use strict";
  const box = document.getElementById("zip-job");
  if (!box || box.dataset.state !== "running") return;
  const bar = document.getElementById("zip-progress");
  async function poll() {
    try {
      const answer = await fetch(window.location.pathname, {
        headers: { Accept: "application/json" },
        cache: "no-store",
      });
      if (answer.ok) {
        const job = await answer.json();
        bar.max = Math.max(job.total, 1);
        bar.value = job.done;
        if (job.state !== "running") {
          window.location.reload();
          return;
        }
      }
    } catch (error) {
      // the server restarting: try again at the next tick
    }
    setTimeout(poll, 2000);
  }
  setTimeout(poll, 2000);
})();
