// Typesets the math that pymdownx.arithmatex (generic mode) leaves in the pages:
// <span class="arithmatex">\(...\)</span> inline and <div class="arithmatex">\[...\]</div>
// as a block. KaTeX is vendored beside this file (javascripts/katex/, MIT licence), so the
// site fetches nothing from a CDN.
function typesetMath() {
  for (const el of document.querySelectorAll(".arithmatex")) {
    const tex = el.textContent.trim();
    const block = tex.startsWith("\\[");
    const body = tex.replace(/^\\[([]/, "").replace(/\\[)\]]$/, "");
    katex.render(body, el, { displayMode: block, throwOnError: false });
  }
}
if (typeof document$ !== "undefined") {
  document$.subscribe(typesetMath); // Material's instant navigation, when it is on
} else {
  document.addEventListener("DOMContentLoaded", typesetMath);
}
