// The static 3-D page's own script (after meshcat's viewer script): builds the viewer,
// unpacks the scene packed into the page's data scripts, and lets the notebook widget
// apply more commands (window.lfdApply) and set the caption (window.lfdCaption).
// tutor/views/scene_page.py puts it into scene3d_page.html, after scene3d_render.js (the
// viewer draws on demand, capped; see there).
var viewer = window.lfdViewer(document.getElementById("meshcat-pane"));
// Apply gzipped, length-prefixed msgpack commands, in order (in slices that yield to input).
async function lfdApply(gz) {
  const stream = new Blob([gz]).stream().pipeThrough(new DecompressionStream("gzip"));
  const buf = new Uint8Array(await new Response(stream).arrayBuffer());
  const view = new DataView(buf.buffer);
  const commands = [];
  let i = 0;
  while (i < buf.length) {
    const n = view.getUint32(i);
    commands.push(buf.slice(i + 4, i + 4 + n));
    i += 4 + n;
  }
  await window.lfdRender.applyCommands(
    commands,
    (c) => viewer.handle_command_bytearray(c),
    buf.length > window.lfdRender.BIG_BYTES
  );
}
function lfdCaption(text) {
  const el = document.getElementById("lfd-caption");
  if (el) el.textContent = text;
}
window.lfdApply = lfdApply;
window.lfdCaption = lfdCaption;
(async function () {
  for (const el of document.querySelectorAll("script.scene-data")) {
    await lfdApply(Uint8Array.from(atob(el.textContent), c => c.charCodeAt(0)));
  }
  document.body.dataset.ready = "1";
})().catch(function (err) {
  document.body.dataset.ready = "error";
  lfdCaption("This browser could not unpack the 3-D scene: " + err);
});
