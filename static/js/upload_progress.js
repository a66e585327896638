// A long record takes a while to send and analyse: say so while the form is posted, and
// keep the button from sending it twice.  The browser posts the form as usual.
document.addEventListener("submit", (event) => {
  const form = event.target.closest("form[data-upload-progress]");
  if (!form || event.defaultPrevented) return;
  const status = form.querySelector(".upload-status");
  if (!status) return;
  const label = status.querySelector("span");
  const bar = status.querySelector("progress");
  bar.removeAttribute("value"); // indeterminate: the server does not report its progress
  label.textContent = label.dataset.sending;
  status.hidden = false;
  form.querySelectorAll("button[type=submit]").forEach((button) => {
    button.disabled = true;
  });
  window.setTimeout(() => {
    label.textContent = label.dataset.analysing;
  }, 4000);
});
