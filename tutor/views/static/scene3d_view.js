// The notebook's 3-D viewer (anywidget ESM of tutor/views/scene_page.py): meshcat's
// page in an iframe. Static (the model's `page`): the page is fed over the widget's comm;
// on (re)load it says hello, the kernel answers with the whole scene for this view id,
// then sends only what changed; after each batch it records data-updates,
// data-applied-at and data-painted-at on the view. Live (the model's `src`): the frame
// shows the live server's page, which gets the scene from its own websocket.
// Both: the guide's messages go kernel -> widget -> frame (postMessage) and
// frame -> widget -> kernel (window.parent.postMessage({lfd: "guide", ...})), see
// tutor/views/scene_guide.py; only messages from this view's own frame are passed on.
// It tells the page whether the view is on screen ('lfd-visible', from its own
// IntersectionObserver) and passes on the kernel's "working" line ('lfd-working').
function render({ model, el }) {
  const id = Math.random().toString(36).slice(2);
  const frame = document.createElement("iframe");
  const src = model.get("src");
  frame.style.width = "100%";
  frame.style.height = model.get("height") + "px";
  frame.style.border = "1px solid #ccc";
  frame.setAttribute("allow", "gamepad");
  frame.title = "The 3-D view of the robot, the tray and the bin";
  // the notebook viewer, or the live server's page (the browser tests tell them apart)
  el.classList.add(src ? "lfd-scene3d-live" : "lfd-scene3d-view");
  el.dataset.updates = "0";
  let ready = false;
  let chain = Promise.resolve();
  const apply = (buffers) => {
    for (const b of buffers) {
      const bytes = b instanceof ArrayBuffer
        ? new Uint8Array(b)
        : new Uint8Array(b.buffer, b.byteOffset, b.byteLength).slice();
      chain = chain.then(() => frame.contentWindow.lfdApply(bytes));
    }
    // what the browser tests read: how many batches were applied, and when (ms since
    // the epoch, comparable with the page's clock); paintedAt once a frame was drawn
    chain = chain
      .then(() => {
        el.dataset.appliedAt = String(Date.now());
        el.dataset.updates = String(Number(el.dataset.updates) + 1);
        const win = frame.contentWindow;
        win.requestAnimationFrame(() => win.requestAnimationFrame(() => {
          el.dataset.paintedAt = String(Date.now());
        }));
      })
      .catch((err) => { el.dataset.error = String(err); });
  };
  // the page draws nothing while the view is off screen (scene3d_render.js): tell it
  let seen = true;
  const post = (data) => { if (frame.contentWindow) frame.contentWindow.postMessage(data, "*"); };
  const observer = "IntersectionObserver" in window
    ? new IntersectionObserver((entries) => {
      seen = entries[entries.length - 1].isIntersecting;
      post({ type: "lfd-visible", visible: seen });
    })
    : null;
  if (observer) observer.observe(el);
  // a guide message for the page: after the scene updates sent before it (static), the
  // links' placements as an ArrayBuffer of their own
  const toFrame = (msg, buffers) => {
    const copy = (buffers || []).map((b) => (b instanceof ArrayBuffer
      ? b.slice(0)
      : b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength)));
    const post = () => {
      if (frame.contentWindow) frame.contentWindow.postMessage({ lfd: "guide", msg, buffers: copy }, "*");
    };
    if (src) post(); else chain = chain.then(post);
  };
  const onMsg = (msg, buffers) => {
    if (msg.type === "full" && msg.to === id) { ready = true; apply(buffers); }
    else if (msg.type === "update" && ready) { apply(buffers); }
    else if (msg.type === "guide") { toFrame(msg, buffers); }
    else if (msg.type === "working") { post({ type: "lfd-working", text: msg.text || "" }); }
  };
  const fromFrame = (event) => {
    if (event.source !== frame.contentWindow) return;
    const data = event.data;
    if (!data || data.lfd !== "guide" || typeof data.msg !== "object") return;
    model.send(data.msg, undefined, data.buffers || []);
  };
  model.on("msg:custom", onMsg);
  window.addEventListener("message", fromFrame);
  // (re)loaded, e.g. when the page moves the output: ask for the whole scene again
  frame.addEventListener("load", () => {
    ready = false;
    post({ type: "lfd-visible", visible: seen });
    model.send({ type: "hello", id: id });
  });
  if (src) frame.src = src; else frame.srcdoc = model.get("page");
  el.appendChild(frame);
  return () => {
    model.off("msg:custom", onMsg);
    window.removeEventListener("message", fromFrame);
    if (observer) observer.disconnect();
  };
}
export default { render };
