// Starts fetching the replay document while the module graph (three.js, ~2 MB) loads;
// replay.js awaits window.__replayDoc.
window.__replayDoc = fetch('/api/replay' + window.location.search).then(async (res) => {
  const doc = await res.json();
  if (!res.ok) throw new Error(doc.error || `HTTP ${res.status}`);
  return doc;
});
window.__replayDoc.catch(() => {});  // reported by replay.js

// WebGL context creation is slow in a software renderer (SwiftShader: about a second):
// start it now, while the modules load; three.js takes this context.
window.__replayGl = (() => {
  const canvas = document.getElementById('scene');
  if (!canvas) return null;
  try {
    return canvas.getContext('webgl2', { antialias: true, preserveDrawingBuffer: true,
      alpha: true, depth: true, stencil: false, premultipliedAlpha: true,
      powerPreference: 'default', failIfMajorPerformanceCaveat: false });
  } catch (err) {
    return null;
  }
})();
