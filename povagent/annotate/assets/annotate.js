"use strict";
// The annotation page. Everything shown from the data is set with textContent (never markup);
// the token is the first part of this page's own path: every URL here is relative to it, so
// each request carries it (and no cookie does), and an answer sends it in a header too.
(function () {
  const token = decodeURIComponent(location.pathname.split("/")[1] || "");
  const headers = { "X-Povagent-Token": token };
  const $ = (id) => document.getElementById(id);
  const el = (tag, text) => { const e = document.createElement(tag); if (text !== undefined) e.textContent = text; return e; };
  let state = null, frames = [], current = 0, mark = null, choice = null, verdict = null, busy = false;

  function keysHelp(q, mode) {
    const keys = [];
    if (frames.length > 1) keys.push("← → images");
    if (tools().length) keys.push("1-" + tools().length + " use a tool (type its values, Enter to go)");
    if (mode === "answer" && q.choices.length) keys.push("1-9 or A-E choose");
    else if (mode === "answer") keys.push("click the image to mark · I J K L move the mark (Shift: 1 px)");
    if (mode === "judge") keys.push("S success · F failure · C can't tell · N note (Esc leaves it)");
    keys.push("Enter submit · Backspace clear");
    $("keys").textContent = "Keys: " + keys.join(" · ");
  }

  // A tool whose parameters hold a pixel (number x and y) is answered by a click on an image.
  const isPointTool = (t) => ["x", "y"].every((n) => t.parameters.some((p) => p.name === n && p.type === "number"));
  const tools = () => (state && state.question && state.question.tools) || [];

  function toolForm(t, i) {
    const box = el("fieldset"); box.dataset.tool = t.name;
    box.append(el("legend", (i + 1) + ". " + t.name));
    box.append(el("p", t.description)); box.lastChild.className = "what";
    const point = isPointTool(t);
    for (const p of t.parameters) {
      if (point && (p.name === "x" || p.name === "y" || p.type === "string")) continue;  // the click fills them
      const id = "tool-" + i + "-" + p.name;
      const label = el("label", p.name); label.htmlFor = id; label.title = p.description;
      const input = el("input"); input.id = id; input.dataset.param = p.name; input.dataset.type = p.type;
      input.type = p.type === "number" || p.type === "integer" ? "number" : "text";
      if (input.type === "number") input.step = p.type === "integer" ? "1" : "any";
      input.setAttribute("aria-label", t.name + " " + p.name + ": " + p.description);
      input.addEventListener("keydown", (e) => { if (e.key === "Enter") { e.preventDefault(); e.stopPropagation(); callTool(t); } });
      box.append(label, input);
    }
    if (point) box.append(el("span", "click the image to place the point"));
    const go = el("button", point ? "Answer (" + (i + 1) + ")" : "Go (" + (i + 1) + ")"); go.type = "button";
    go.setAttribute("aria-keyshortcuts", String(i + 1));
    go.addEventListener("click", () => callTool(t));
    box.append(go);
    return box;
  }

  function callTool(t) {
    const box = $("tools").querySelector("fieldset[data-tool='" + CSS.escape(t.name) + "']");
    const args = {};
    for (const input of box.querySelectorAll("input")) {
      if (input.value === "") { input.focus(); return; }
      args[input.dataset.param] = input.dataset.type === "string" ? input.value : Number(input.value);
    }
    const body = { tool: t.name, arguments: args };
    if (isPointTool(t)) {
      if (!mark) { $("status").textContent = "Click the image first, then answer."; return; }
      Object.assign(body.arguments, { x: mark.x, y: mark.y });
      body.image = mark.image;
    }
    send(body);
  }

  function imageUrl(q, i) { return "api/image/" + q.number + "/" + i; }

  function showFrame(i) {
    if (!frames.length) return;
    current = (i + frames.length) % frames.length;
    const f = frames[current];
    $("view").src = imageUrl(state.question, f.image);
    $("view").alt = f.label || ("image " + (current + 1));
    $("frame-label").textContent = (f.label || "image") + " (" + (current + 1) + " of " + frames.length + ")";
    for (const b of $("strip").children) b.setAttribute("aria-current", String(Number(b.dataset.index) === current));
    drawMark();
  }

  function drawMark() {
    const m = $("marker"), f = frames[current];
    const point = state.mode === "judge" ? state.question.point : mark;
    if (!point || !f || point.image !== f.image) { m.hidden = true; return; }
    m.hidden = false;
    m.style.left = (100 * point.x / f.width) + "%";
    m.style.top = (100 * point.y / f.height) + "%";
  }

  function ready() {
    const q = state && state.question;
    let ok = false;
    if (q && state.mode === "answer") ok = q.choices.length ? choice !== null : mark !== null;
    if (q && tools().length) ok = mark !== null && tools().some(isPointTool);
    if (q && state.mode === "judge") ok = verdict !== null;
    $("submit").disabled = !ok || busy;
  }

  function render() {
    const q = state.question;
    $("progress").textContent = state.who + ": " + state.done + " of " + state.total + " saved";
    $("prompt").replaceChildren(); $("choices").replaceChildren(); $("strip").replaceChildren(); $("tools").replaceChildren();
    mark = null; choice = null; verdict = null; frames = [];
    $("note").value = "";
    if (!q) {
      $("viewer").hidden = true; $("verdicts").hidden = true;
      $("status").textContent = state.finished ? "All done. Thank you: you may close this tab." : "Waiting for the next item…";
      ready();
      return;
    }
    $("status").textContent = state.mode === "judge"
      ? "Is the red mark where the sentence places the object, from the speaker's view?"
      : q.choices.length ? "Choose the answer."
      : (q.tools || []).length ? "Look around with the tools; answer by clicking the point in an image you were shown, then Enter."
      : "Click the point the sentence describes, in the image where you see it.";
    for (const part of q.parts) {
      if (part.text !== undefined) $("prompt").append(el("p", part.text));
      else frames.push(part);
    }
    frames.forEach((f, i) => {
      const b = el("button"); b.type = "button"; b.dataset.index = String(i); b.setAttribute("role", "listitem");
      const img = el("img"); img.src = imageUrl(q, f.image); img.alt = f.label || ("image " + (i + 1));
      b.append(img); b.addEventListener("click", () => showFrame(i));
      $("strip").append(b);
    });
    $("viewer").hidden = frames.length === 0;
    $("strip").hidden = frames.length < 2;
    $("frame-nav").hidden = frames.length < 2;
    $("verdicts").hidden = state.mode !== "judge";
    if (state.mode === "answer") q.choices.forEach(([label, text], i) => {
      const b = el("button", label + ". " + text); b.type = "button"; b.dataset.choice = label;
      b.setAttribute("aria-keyshortcuts", String(i + 1)); b.setAttribute("aria-pressed", "false");
      b.addEventListener("click", () => choose(label));
      $("choices").append(b);
    });
    (q.tools || []).forEach((t, i) => $("tools").append(toolForm(t, i)));
    for (const b of $("verdicts").querySelectorAll("button")) b.setAttribute("aria-pressed", "false");
    // judge mode: the answered frame; an episode: its newest view; else the first image
    const start = state.mode === "judge" ? frames.findIndex((f) => f.image === q.point.image) : (tools().length ? frames.length - 1 : 0);
    showFrame(Math.max(0, start));
    keysHelp(q, state.mode);
    ready();
  }

  function choose(label) {
    choice = label;
    for (const b of $("choices").children) b.setAttribute("aria-pressed", String(b.dataset.choice === label));
    ready();
  }

  function judge(v) {
    verdict = v;
    for (const b of $("verdicts").querySelectorAll("button")) b.setAttribute("aria-pressed", String(b.dataset.verdict === v));
    ready();
  }

  function place(x, y) {
    const f = frames[current];
    mark = { image: f.image, x: Math.min(f.width, Math.max(0, x)), y: Math.min(f.height, Math.max(0, y)) };
    drawMark(); ready();
  }

  $("view").addEventListener("click", (e) => {
    if (state.mode !== "answer" || state.question.choices.length) return;
    if (tools().length && !tools().some(isPointTool)) return;
    const r = $("view").getBoundingClientRect(), f = frames[current];
    // the pixel in the frame's own coordinates, whatever size the page shows it at
    place((e.clientX - r.left) * f.width / r.width, (e.clientY - r.top) * f.height / r.height);
  });

  async function submit() {
    if ($("submit").disabled) return;
    const q = state.question, body = {};
    if (tools().length) return callTool(tools().find(isPointTool));
    if (state.mode === "judge") { body.verdict = verdict; body.note = $("note").value; }
    else if (q.choices.length) body.choice = choice;
    else Object.assign(body, mark);
    send(body);
  }

  async function send(answer) {
    if (busy) return;
    const body = { question: state.question.number, ...answer };
    busy = true; ready();
    $("status").textContent = "Saving…";
    try {
      const r = await fetch("api/" + state.mode, { method: "POST", headers: { ...headers, "Content-Type": "application/json" }, body: JSON.stringify(body) });
      const reply = await r.json();
      if (!r.ok) {
        $("status").textContent = "Not saved: " + (reply.error || r.status);
        // a question that is no longer open (asked again after a long wait): show the open one
        if (r.status === 422 && / is not open|not the one shown/.test(reply.error || "")) setTimeout(poll, 1500);
        return;
      }
    } catch (err) {
      $("status").textContent = "Not saved (the server is gone?): reload this page to resume.";
      return;
    } finally { busy = false; ready(); }
    poll();
  }

  async function poll() {
    try {
      const r = await fetch("api/state", { headers });
      if (!r.ok) { $("status").textContent = "Refused (" + r.status + "): open the address the command printed."; return; }
      state = await r.json();
    } catch (err) {
      $("status").textContent = "The server is gone: start it again and reload this page to resume.";
      return;
    }
    render();
    if (!state.question && !state.finished) setTimeout(poll, 300);
  }

  $("prev").addEventListener("click", () => showFrame(current - 1));
  $("next").addEventListener("click", () => showFrame(current + 1));
  $("submit").addEventListener("click", submit);
  $("clear").addEventListener("click", () => { mark = null; choice = null; verdict = null; render(); });
  for (const b of $("verdicts").querySelectorAll("button")) b.addEventListener("click", () => judge(b.dataset.verdict));

  document.addEventListener("keydown", (e) => {
    if (!state || !state.question) return;
    if (e.target.closest && e.target.closest("#tools")) return;  // typing a tool's argument
    if (e.target === $("note")) { if (e.key === "Escape") $("note").blur(); else if (e.key === "Enter") submit(); return; }
    const q = state.question, k = e.key;
    if (k === "ArrowLeft") showFrame(current - 1);
    else if (k === "ArrowRight") showFrame(current + 1);
    else if (k === "Enter") submit();
    else if (k === "Backspace") { mark = null; choice = null; drawMark(); render(); }
    else if (state.mode === "judge" && "sfc".includes(k.toLowerCase()) && k.length === 1) judge({ s: "success", f: "failure", c: "cant_tell" }[k.toLowerCase()]);
    else if (state.mode === "judge" && k.toLowerCase() === "n") $("note").focus();
    else if (tools().length && /^[1-9]$/.test(k) && Number(k) <= tools().length) {
      const t = tools()[Number(k) - 1], empty = $("tools").querySelectorAll("fieldset")[Number(k) - 1].querySelector("input");
      if (empty && empty.value === "") empty.focus(); else callTool(t);
    }
    else if (state.mode === "answer" && q.choices.length && /^[1-9]$/.test(k) && Number(k) <= q.choices.length) choose(q.choices[Number(k) - 1][0]);
    else if (state.mode === "answer" && q.choices.length && q.choices.some((c) => c[0] === k.toUpperCase())) choose(k.toUpperCase());
    else if (state.mode === "answer" && !q.choices.length && "ijkl".includes(k.toLowerCase()) && k.length === 1) {
      const f = frames[current], step = e.shiftKey ? 1 : 10;
      const m = mark && mark.image === f.image ? mark : { x: f.width / 2, y: f.height / 2 };
      const d = { i: [0, -step], k: [0, step], j: [-step, 0], l: [step, 0] }[k.toLowerCase()];
      place(m.x + d[0], m.y + d[1]);
    } else return;
    e.preventDefault();
  });

  poll();
})();
