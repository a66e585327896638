// LTI pages: submit a form marked data-autosubmit (the deep-linking response to the LMS),
// and tell the LMS that dynamic registration is done (this script's data-lti-close).
document.querySelectorAll("form[data-autosubmit]").forEach((form) => form.submit());
if (document.currentScript && document.currentScript.hasAttribute("data-lti-close")) {
  (window.opener || window.parent).postMessage({ subject: "org.imsglobal.lti.close" }, "*");
}
