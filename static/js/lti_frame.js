// A launch inside an LMS frame (app/lti/frame_launch.py): tie the OIDC login to this
// browser through the LMS's platform storage (1EdTech LTI Client Side OIDC Launch:
// lti.put_data / lti.get_data over postMessage), else through the partitioned state
// cookie, else offer a new window.  Answers count only from the LMS's own origin.
(function () {
  "use strict";
  const box = document.getElementById("lti-frame");
  if (!box) return;
  const d = box.dataset;
  const WAIT_MS = 3000;

  function storageWindow() {
    const host = window.opener || (window.parent !== window ? window.parent : null);
    if (!d.target || !host || !d.platformOrigin) return null;
    if (d.target === "_parent") return host;
    try {
      return host.frames[d.target] || null;
    } catch (error) {
      return null;
    }
  }

  function newId() {
    if (window.crypto && crypto.randomUUID) return crypto.randomUUID();
    return String(Date.now()) + String(Math.random()).slice(2);
  }

  // one request to the LMS; its answer, or null on an error, a timeout or no storage
  function ask(subject, fields) {
    const target = storageWindow();
    if (!target) return Promise.resolve(null);
    const id = newId();
    return new Promise((resolve) => {
      function done(answer) {
        clearTimeout(timer);
        window.removeEventListener("message", listen);
        resolve(answer);
      }
      function listen(event) {
        const data = event.data;
        if (event.origin !== d.platformOrigin || !data || typeof data !== "object") return;
        if (data.subject !== subject + ".response" || data.message_id !== id) return;
        done(data.error ? null : data);
      }
      const timer = setTimeout(() => done(null), WAIT_MS);
      window.addEventListener("message", listen);
      target.postMessage(Object.assign({ subject: subject, message_id: id }, fields), d.platformOrigin);
    });
  }

  async function put(key, value) {
    const answer = await ask("lti.put_data", { key: key, value: value });
    return answer !== null && answer.key === key;
  }

  async function get(key) {
    const answer = await ask("lti.get_data", { key: key });
    return answer === null ? null : answer.value;
  }

  function show(id) {
    document.getElementById("lti-wait").hidden = true;
    document.getElementById(id).hidden = false;
  }

  async function cookieArrived() {
    try {
      const answer = await fetch("/lti/state-check?state=" + encodeURIComponent(d.state), {
        credentials: "same-origin",
        cache: "no-store",
      });
      return answer.ok && (await answer.json()).cookie === true;
    } catch (error) {
      return false;
    }
  }

  async function login() {
    const stored =
      d.target && (await put("state_" + d.state, d.state)) && (await put("nonce_" + d.nonce, d.nonce));
    if (stored || (await cookieArrived())) {
      window.location.replace(d.authUrl);
      return;
    }
    show("lti-new-window");
  }

  async function confirm() {
    const state = await get("state_" + d.state);
    const nonce = d.nonce ? await get("nonce_" + d.nonce) : null;
    if (state === d.state && nonce === d.nonce) {
      const form = document.getElementById("lti-confirm");
      form.elements.lti_platform_state.value = state;
      form.submit();
      return;
    }
    show("lti-unconfirmed");
  }

  (d.mode === "login" ? login : confirm)();
})();
