// Starts fetching the replay document while the module graph (three.js, ~2 MB) loads;
// replay.js awaits window.__replayDoc.
window.__replayDoc = fetch('/api/replay' + window.location.search).then(async (res) => {
  const doc = await res.json();
  if (!res.ok) throw new Error(doc.error || `HTTP ${res.status}`);
  return doc;
});
window.__replayDoc.catch(() => {});  // reported by replay.js
