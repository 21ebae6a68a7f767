// jswim report: the run browser. Everything it shows is in this page (no request is made).
(function () {
  "use strict";
  var D = JSON.parse(document.getElementById("report-data").textContent);
  var runs = D.runs;
  var COLORS = { llm: "#0072B2", qlearning: "#D55E00", random: "#555555", ppo: "#009E73", stroke: "#000000", controller: "#000000", zermelo: "#CC79A7" };
  var NAMES = { llm: "LLM", qlearning: "Q-learning", random: "random policy", ppo: "PPO (real ROC)", stroke: "square stroke",
    controller: "steering controller", zermelo: "Zermelo (least-time point steerer)" };
  var FLOW = "#7EA6C8";  // a background flow's arrows (jswim.figures.flow_plots.FLOW_COLOR)
  var LIST_MAX = 400;
  var st = { filters: {}, sel: null, data: null, k: 0, timer: null, fps: 4, loading: 0 };

  function esc(s) {
    return String(s).replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;").replace(/"/g, "&quot;");
  }
  function fmt(key, v) {
    if (v === null || v === undefined || v === "") return "\u2013";
    if (key === "direction") return v > 0 ? "+x" : "\u2212x";
    if (key === "success") return v ? "yes" : "no";
    return String(v);
  }
  function num(v, d) { return (v === null || v === undefined) ? "\u2013" : Number(v).toFixed(d); }
  function signed(v, d) { return (v >= 0 ? "+" : "") + Number(v).toFixed(d); }
  function action(a) { return "[" + a[0] + ", " + a[1] + "]"; }
  // One sign convention for every number on the page: X/a toward the run's target direction
  // (a -x run that swims to x = -0.62 a reads +0.62), always labelled with that direction.
  function toward(d) { return "X/a toward " + fmt("direction", d.direction); }
  // Where a run is at step k: X/a toward its direction, or (a navigation run) its (x, y) in the plane.
  function place(d, k) {
    if ((d.targets || []).length) return "(x, y)/a = (" + signed(d.x[k], 3) + ", " + signed(d.y[k], 3) + ")";
    return toward(d) + " = " + signed(d.direction * d.x[k], 4);
  }

  // -- filters and the run list ------------------------------------------------------------------
  function values(key) {
    var seen = {}, out = [];
    runs.forEach(function (r) { var t = fmt(key, r[key]); if (!(t in seen)) { seen[t] = 1; out.push(t); } });
    return out.sort(function (a, b) { var x = parseFloat(a), y = parseFloat(b);
      return (isNaN(x) || isNaN(y)) ? (a < b ? -1 : a > b ? 1 : 0) : x - y; });
  }
  function sameSplit(a, b) {  // two filters that split the runs the same way say the same thing twice
    var ab = {}, ba = {};
    for (var i = 0; i < runs.length; i++) {
      var x = fmt(a, runs[i][a]), y = fmt(b, runs[i][b]);
      if ((x in ab && ab[x] !== y) || (y in ba && ba[y] !== x)) return false;
      ab[x] = y; ba[y] = x;
    }
    return true;
  }
  // The paper's symbols keep their own spelling (n_ht, not "n ht").
  var FILTER_LABELS = { n_ht: "n_ht", zeta: "\u03b6" };

  function buildFilters() {
    var box = document.getElementById("filters"), shown = [];
    D.filters.forEach(function (key) {
      var vals = values(key);
      if (vals.length < 2) return;
      if (shown.some(function (k) { return sameSplit(k, key); })) return;
      shown.push(key);
      var label = document.createElement("label");
      label.textContent = FILTER_LABELS[key] || key.replace("_", " ");
      var sel = document.createElement("select");
      sel.id = "filter-" + key;
      sel.innerHTML = '<option value="">all</option>' + vals.map(function (v) {
        return '<option value="' + esc(v) + '">' + esc(v) + "</option>"; }).join("");
      sel.addEventListener("change", function () { st.filters[key] = sel.value; renderList(); });
      label.appendChild(sel);
      box.appendChild(label);
    });
  }
  function matches(r) {
    for (var key in st.filters) {
      if (st.filters[key] && fmt(key, r[key]) !== st.filters[key]) return false;
    }
    return true;
  }
  function renderList() {
    // The page lists runs in the order the writer sorted them: by the study's axes (agent, swimmer,
    // direction, group, zeta, n_ht, variant, start, replicate), never by when they finished.
    var m = runs.filter(matches).sort(function (a, b) { return a.i - b.i; });
    var shown = m.slice(0, LIST_MAX);
    document.getElementById("run-count").textContent = m.length + " of " + runs.length + " runs" +
      (m.length > LIST_MAX ? " (the first " + LIST_MAX + " listed; narrow the filters for the rest)" : "");
    var rows = shown.map(function (r) {
      return '<tr data-i="' + r.i + '"' + (r.i === st.sel ? ' class="sel"' : "") + "><td>" + esc(r.run_id) +
        "</td><td>" + (r.status && r.status !== "done" ? '<span class="error">' + esc(r.status) + "</span>" :
        (r.success ? "yes" : "no")) + '</td><td class="num">' + (r.signed_final_x === null || r.signed_final_x === undefined ? "\u2013" :
        signed(r.signed_final_x, 3)) + "</td></tr>";
    });
    document.getElementById("run-list").innerHTML =
      "<thead><tr><th>run</th><th>success</th><th title=\"X/a after the last step, positive toward the run's target direction\">X/a end toward target</th></tr></thead><tbody>" + rows.join("") + "</tbody>";
  }

  // -- one run: decoding -------------------------------------------------------------------------
  function decode(i) {
    var text = document.getElementById("run-" + i).textContent;
    var bin = atob(text), bytes = new Uint8Array(bin.length);
    for (var j = 0; j < bin.length; j++) bytes[j] = bin.charCodeAt(j);
    if (typeof DecompressionStream === "undefined") {
      return Promise.reject(new Error("this browser has no DecompressionStream (Chrome 80+, Firefox 113+, Safari 16.4+ do)"));
    }
    var stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
    return new Response(stream).text().then(JSON.parse);
  }
  function select(i) {
    pause();
    st.sel = i;
    var token = ++st.loading;
    document.querySelectorAll("#run-list tr.sel").forEach(function (tr) { tr.classList.remove("sel"); });
    var tr = document.querySelector('#run-list tr[data-i="' + i + '"]');
    if (tr) tr.classList.add("sel");
    return decode(i).then(function (d) {
      if (token !== st.loading) return;
      st.data = d; st.k = 0; prepare(d); buildViewer(); show(0);
    }).catch(function (e) {
      document.getElementById("viewer").innerHTML = '<p class="error">cannot open this run: ' + esc(e.message) + "</p>";
    });
  }
  function prepare(d) {
    if (!d.x || !d.x.length) return;
    var x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity, r = d.planar ? 0 : 1, ext = 0;
    d.bodies = d.bodies || d.pts.map(function (f) { return [f]; });
    d.pos = d.pos || d.x.map(function (x, i) { return [[x, d.y[i]]]; });
    d.bodies.forEach(function (frame) { frame.forEach(function (body) {
      var bx0 = Infinity, bx1 = -Infinity;
      body.forEach(function (p) {
        x0 = Math.min(x0, p[0] - r); x1 = Math.max(x1, p[0] + r); y0 = Math.min(y0, p[1] - r); y1 = Math.max(y1, p[1] + r);
        bx0 = Math.min(bx0, p[0] - r); bx1 = Math.max(bx1, p[0] + r);
      });
      ext = Math.max(ext, bx1 - bx0);
    }); });
    if (d.wall) y0 = Math.min(y0, -0.6);
    (d.obstacles || []).forEach(function (o) {
      x0 = Math.min(x0, o[0] - o[2]); x1 = Math.max(x1, o[0] + o[2]); y0 = Math.min(y0, o[1] - o[2]); y1 = Math.max(y1, o[1] + o[2]);
    });
    (d.targets || []).forEach(function (g) {
      var v = d.target_v || [0, 0], n = d.x.length;
      [[g[0], g[1]], [g[0] + v[0] * n, g[1] + v[1] * n]].forEach(function (q) {
        x0 = Math.min(x0, q[0] - g[2]); x1 = Math.max(x1, q[0] + g[2]); y0 = Math.min(y0, q[1] - g[2]); y1 = Math.max(y1, q[1] + g[2]);
      });
    });
    d.box = [x0 - 1, x1 + 1, y0 - 1, y1 + 1];
    // A long run is followed by a window that always holds the whole swimmer (an NG swimmer at arms
    // (10, 10) is 22 a long), never a fixed 16 a; a pair far apart is shown whole.
    d.followW = Math.max(16, ext + 4);
    d.follow = d.bodies[0].length === 1 && (x1 - x0) > Math.max(20, d.followW + 4);
  }

  // -- the viewer --------------------------------------------------------------------------------
  function buildViewer() {
    var d = st.data, r = runs[st.sel], v = document.getElementById("viewer");
    if (!d.x || !d.x.length) {
      v.innerHTML = '<h3>' + esc(r.run_id) + '</h3><p class="error">no steps recorded' +
        (d.error ? ": " + esc(d.error) : "") + "</p>";
      return;
    }
    var n = d.actions.length;
    var stroke = d.stroke ? "the success criterion found the stroke from step " + (d.stroke[0] + 1) + " (period " +
      d.stroke[1] + "): cycles at steps " + cycles(d).map(function (c) { return c[0] + "\u2013" + c[1]; }).join(", ") :
      "the success criterion found no qualifying stroke";
    var name = r.agent === "llm" ? NAMES.llm : d.label || NAMES[r.agent];
    var who = (name || r.agent) + (r.agent === "llm" && D.model ? " (" + D.model + ")" : "");
    var nav = (d.targets || []).length > 0;  // a navigation run: its target, not a direction
    if (nav) stroke = r.success ? "target reached" : "target not reached";
    var bits = [who, d.point ? "a point steering at the swimming speed (no body, no strokes)" : d.model + " swimmer",
      nav ? d.world : "target " + fmt("direction", r.direction)];
    if (r.zeta !== null && r.zeta !== undefined) bits.push("\u03b6 = " + r.zeta);
    if (r.init) bits.push("start " + r.init);
    if (r.n_ht !== null && r.n_ht !== undefined) bits.push("n_ht " + r.n_ht);
    if (r.variant) bits.push("variant " + r.variant);
    if (r.group) bits.push("group " + r.group);
    var html = '<h3 id="run-title">' + esc(r.run_id) + "</h3><p>" + esc(bits.join(" \u00b7 ")) + "<br/>success: " +
      (r.success ? "yes" : "no") + (nav ? (r.steps_to_target ? " \u00b7 " + r.steps_to_target + " steps to the target" : "") :
      " \u00b7 X/a end toward " + fmt("direction", r.direction) + " " + signed(r.signed_final_x || 0, 4)) +
      " \u00b7 " + esc(stroke) + (d.replayed ? ' \u00b7 <span class="error">y and orientation replayed (not recorded in this folder)</span>' : "") +
      '</p><canvas class="swim" id="swim" width="900" height="340"></canvas>' +
      (d.flow ? '<p class="legend note" id="flow-legend"><span class="flow-key" style="width:16px;height:3px;background:' + FLOW +
        '"></span>' + esc(d.flow.legend) + "</p>" : "") +
      '<div class="controls"><button id="b-first" title="first step">|\u25c0</button>' +
      '<button id="b-back" title="step back (\u2190)">\u25c0</button>' +
      '<button id="b-play" title="play / pause (space)">\u25b6</button>' +
      '<button id="b-fwd" title="step forward (\u2192)">\u25b6|</button>' +
      '<button id="b-last" title="last step">\u25b6\u25b6|</button>' +
      '<input type="range" id="scrub" min="0" max="' + n + '" value="0"/>' +
      '<span id="step-label"></span><label>speed <select id="speed">' +
      [1, 2, 4, 8, 16].map(function (f) { return '<option value="' + f + '"' + (f === st.fps ? " selected" : "") + ">" +
        f + " steps/s</option>"; }).join("") + "</select></label></div>" +
      '<div class="timeline" id="timeline">' + d.actions.map(function (_, i) {
        var c = [];
        if (d.stuck[i]) c.push("stuck");
        if (d.stroke && i >= d.stroke[0]) c.push("stroke");
        if (d.failed[i]) c.push("failed");
        if (d.cleared[i]) c.push("cleared");
        return '<div data-k="' + (i + 1) + '" class="' + c.join(" ") + '" title="step ' + (i + 1) + '"></div>';
      }).join("") + '</div><p class="legend note">steps:<span style="background:#9fc3e0"></span>moved' +
      '<span style="background:#c9c9c9"></span>stuck<span style="background:#009e73"></span>stroke found by the criterion' +
      '<span style="background:#e69f00"></span>no valid reply<span style="box-shadow:inset 3px 0 0 #b00000;background:#fff"></span>history cleared</p>' +
      '<div class="step" id="step"></div>';
    v.innerHTML = html;
    document.getElementById("b-first").onclick = function () { pause(); show(0); };
    document.getElementById("b-back").onclick = function () { pause(); show(st.k - 1); };
    document.getElementById("b-fwd").onclick = function () { pause(); show(st.k + 1); };
    document.getElementById("b-last").onclick = function () { pause(); show(n); };
    document.getElementById("b-play").onclick = function () { st.timer ? pause() : play(); };
    document.getElementById("scrub").oninput = function (e) { pause(); show(parseInt(e.target.value, 10)); };
    document.getElementById("speed").onchange = function (e) {
      st.fps = parseInt(e.target.value, 10); if (st.timer) { pause(); play(); } };
    document.getElementById("timeline").onclick = function (e) {
      var k = e.target.getAttribute("data-k"); if (k) { pause(); show(parseInt(k, 10)); } };
  }
  function cycles(d) {
    var out = [], n = d.actions.length;
    if (!d.stroke) return out;
    for (var s = d.stroke[0]; s + d.stroke[1] <= n; s += d.stroke[1]) out.push([s + 1, s + d.stroke[1]]);
    return out;
  }
  function play() {
    var d = st.data;
    if (!d || !d.x || !d.x.length) return;
    if (st.k >= d.actions.length) show(0);
    document.getElementById("b-play").textContent = "||";
    st.timer = setInterval(function () {
      if (st.k >= st.data.actions.length) { pause(); return; }
      show(st.k + 1);
    }, 1000 / st.fps);
  }
  function pause() {
    if (st.timer) clearInterval(st.timer);
    st.timer = null;
    var b = document.getElementById("b-play");
    if (b) b.textContent = "\u25b6";
  }
  function show(k) {
    var d = st.data;
    if (!d || !d.x || !d.x.length) return;
    k = Math.max(0, Math.min(d.actions.length, k));
    st.k = k;
    draw(d, k);
    document.getElementById("scrub").value = k;
    document.getElementById("step-label").textContent = "step " + k + " / " + d.actions.length;
    var cells = document.getElementById("timeline").children;
    for (var i = 0; i < cells.length; i++) cells[i].classList.toggle("now", i === k - 1);
    document.getElementById("step").innerHTML = stepHtml(d, k);
  }

  function draw(d, k) {
    var cv = document.getElementById("swim"), ctx = cv.getContext("2d");
    var W = cv.width, H = cv.height, b = d.box.slice(), r = runs[st.sel];
    if (d.follow) { var w = d.followW, c = d.pos[k][0][0]; b[0] = c - w / 2; b[1] = c + w / 2; }
    var s = Math.min(W / (b[1] - b[0]), H / (b[3] - b[2]));
    var ox = (W - s * (b[1] - b[0])) / 2, oy = (H - s * (b[3] - b[2])) / 2;
    function X(x) { return ox + (x - b[0]) * s; }
    function Y(y) { return H - oy - (y - b[2]) * s; }
    st.X = X; st.Y = Y;  // the last drawing's map from a to canvas pixels (for tests)
    ctx.fillStyle = "#eaf3fa"; ctx.fillRect(0, 0, W, H);
    ctx.strokeStyle = "#d5e4f0"; ctx.lineWidth = 1;
    for (var gx = Math.ceil(b[0]); gx <= b[1]; gx++) { ctx.beginPath(); ctx.moveTo(X(gx), 0); ctx.lineTo(X(gx), H); ctx.stroke(); }
    for (var gy = Math.ceil(b[2]); gy <= b[3]; gy++) { ctx.beginPath(); ctx.moveTo(0, Y(gy)); ctx.lineTo(W, Y(gy)); ctx.stroke(); }
    ctx.setLineDash([4, 4]); ctx.strokeStyle = "#888"; ctx.beginPath(); ctx.moveTo(X(0), 0); ctx.lineTo(X(0), H); ctx.stroke();
    ctx.setLineDash([]);
    st.flowDrawn = d.flow ? drawFlow(ctx, d.flow, X, Y, s, W, H) : 0;
    if (d.wall) {  // the no-slip wall: the plane y = 0, the fluid above it
      ctx.fillStyle = "#d9cfc2"; ctx.fillRect(0, Y(0), W, H - Y(0));
      ctx.strokeStyle = "#6b5b45"; ctx.lineWidth = 2; ctx.beginPath(); ctx.moveTo(0, Y(0)); ctx.lineTo(W, Y(0)); ctx.stroke();
      ctx.fillStyle = "#6b5b45"; ctx.font = "12px sans-serif"; ctx.fillText("wall", W - 40, Math.min(H - 30, Y(0) + 14));
    }
    (d.obstacles || []).forEach(function (o) {
      ctx.beginPath(); ctx.arc(X(o[0]), Y(o[1]), o[2] * s, 0, 2 * Math.PI);
      ctx.fillStyle = "#9a8c7a"; ctx.fill(); ctx.strokeStyle = "#6b5b45"; ctx.lineWidth = 1; ctx.stroke();
    });
    (d.targets || []).forEach(function (g, n) {  // a navigation task's targets (a moving one: at step k)
      var v = d.target_v || [0, 0], gx = g[0] + v[0] * k, gy = g[1] + v[1] * k;
      ctx.beginPath(); ctx.arc(X(gx), Y(gy), g[2] * s, 0, 2 * Math.PI);
      ctx.strokeStyle = "#B00000"; ctx.lineWidth = 1.5; ctx.stroke();
      ctx.beginPath(); ctx.moveTo(X(gx) - 5, Y(gy) - 5); ctx.lineTo(X(gx) + 5, Y(gy) + 5);
      ctx.moveTo(X(gx) - 5, Y(gy) + 5); ctx.lineTo(X(gx) + 5, Y(gy) - 5); ctx.stroke();
      if (d.targets.length > 1) { ctx.fillStyle = "#B00000"; ctx.font = "11px sans-serif"; ctx.fillText(String(n + 1), X(gx) + 6, Y(gy) - 6); }
    });
    var color = COLORS[r.agent] || "#333";
    var swColors = [color, "#CC79A7", "#56B4E9", "#F0E442"];
    for (var j = 0; j < d.bodies[k].length; j++) {
      ctx.strokeStyle = swColors[j % swColors.length]; ctx.globalAlpha = 0.7; ctx.lineWidth = 1.5; ctx.beginPath();
      for (var i = 0; i <= k; i++) {
        var q = d.pos[i][j]; if (i) ctx.lineTo(X(q[0]), Y(q[1])); else ctx.moveTo(X(q[0]), Y(q[1]));
      }
      ctx.stroke();
      if (d.stroke && k > d.stroke[0]) {
        ctx.strokeStyle = "#009e73"; ctx.lineWidth = 4; ctx.beginPath();
        for (i = d.stroke[0]; i <= k; i++) {
          q = d.pos[i][j]; if (i > d.stroke[0]) ctx.lineTo(X(q[0]), Y(q[1])); else ctx.moveTo(X(q[0]), Y(q[1]));
        }
        ctx.stroke();
      }
    }
    ctx.globalAlpha = 1;
    st.drawn = d.bodies[k].length;
    for (j = 0; j < d.bodies[k].length && !d.point; j++) { drawBody(d.bodies[k][j], swColors[j % swColors.length]); }
    function drawBody(p, color) {
    if (d.planar) {
      ctx.strokeStyle = "#111"; ctx.lineWidth = Math.max(3, 0.09 * s); ctx.lineCap = "round"; ctx.lineJoin = "round";
      ctx.beginPath(); p.forEach(function (q, j) { if (j) ctx.lineTo(X(q[0]), Y(q[1])); else ctx.moveTo(X(q[0]), Y(q[1])); });
      ctx.stroke();
      ctx.fillStyle = color;
      for (i = 1; i < p.length - 1; i++) { ctx.beginPath(); ctx.arc(X(p[i][0]), Y(p[i][1]), Math.max(3, 0.06 * s), 0, 2 * Math.PI); ctx.fill(); }
    } else {
      ctx.strokeStyle = "#555"; ctx.lineWidth = 1.5; ctx.beginPath();
      ctx.moveTo(X(p[0][0]), Y(p[0][1])); ctx.lineTo(X(p[p.length - 1][0]), Y(p[p.length - 1][1])); ctx.stroke();
      p.forEach(function (q) {
        ctx.beginPath(); ctx.arc(X(q[0]), Y(q[1]), s, 0, 2 * Math.PI);
        ctx.fillStyle = "#fff"; ctx.fill(); ctx.strokeStyle = color; ctx.lineWidth = 2; ctx.stroke();
      });
    }
    }
    ctx.strokeStyle = color; ctx.lineWidth = 2; var cx = X(d.pos[k][0][0]), cy = Y(d.pos[k][0][1]);
    ctx.beginPath(); ctx.moveTo(cx - 6, cy); ctx.lineTo(cx + 6, cy); ctx.moveTo(cx, cy - 6); ctx.lineTo(cx, cy + 6); ctx.stroke();
    // scale bar (one a) and the text of the step
    ctx.strokeStyle = "#333"; ctx.lineWidth = 2; ctx.beginPath(); ctx.moveTo(12, H - 14); ctx.lineTo(12 + s, H - 14); ctx.stroke();
    ctx.fillStyle = "#333"; ctx.font = "12px sans-serif"; ctx.fillText("a", 12 + s / 2 - 3, H - 20);
    ctx.font = "13px monospace";
    ctx.fillText("step " + k + "/" + d.actions.length + "   " + place(d, k), 10, 18);
    if (k > 0) {
      var ev = [];
      if (d.stuck[k - 1] && !d.point) ev.push("stuck");
      if (d.cleared[k - 1]) ev.push("history cleared");
      if (d.failed[k - 1]) ev.push("no valid reply");
      if (d.stroke && k - 1 >= d.stroke[0]) ev.push("stroke cycle " + (Math.floor((k - 1 - d.stroke[0]) / d.stroke[1]) + 1));
      if (!d.point) ctx.fillText("action " + action(d.actions[k - 1]) + "  " + ev.join(", "), 10, 36);
      var step = d.steps[k - 1];
      if (step && step.attempts && step.attempts.length) {
        var t = String(step.attempts[step.attempts.length - 1].text || "").replace(/\s+/g, " ");
        ctx.fillText("reply: " + (t.length > 60 ? t.slice(0, 57) + "..." : t), 10, 54);
      }
    }
    if (!(d.targets || []).length) ctx.fillText("target " + (d.direction > 0 ? "\u2192" : "\u2190"), W - 90, H - 12);
  }

  // A background flow under the track: an arrow of its velocity at each lattice point in view,
  // the fastest 0.8 of the lattice spacing long; returns how many were drawn.
  function drawFlow(ctx, f, X, Y, s, W, H) {
    if (f.label) { ctx.fillStyle = "#4d7aa3"; ctx.font = "12px sans-serif"; ctx.fillText("flow: " + f.label, W - 170, 18); }
    if (!f.arrows || !f.arrows.length || !(f.max > 0)) return 0;
    var n = 0, L = 0.8 * f.spacing / f.max;
    ctx.save();
    ctx.strokeStyle = FLOW; ctx.fillStyle = FLOW; ctx.lineWidth = 1.2;
    f.arrows.forEach(function (q) {
      var ax = X(q[0] - q[2] * L / 2), ay = Y(q[1] - q[3] * L / 2);
      var bx = X(q[0] + q[2] * L / 2), by = Y(q[1] + q[3] * L / 2);
      var len = Math.hypot(bx - ax, by - ay);
      if (len < 2 || Math.max(ax, bx) < 0 || Math.min(ax, bx) > W || Math.max(ay, by) < 0 || Math.min(ay, by) > H) return;
      var ux = (bx - ax) / len, uy = (by - ay) / len, hd = Math.min(6, 0.4 * len);
      ctx.beginPath(); ctx.moveTo(ax, ay); ctx.lineTo(bx, by); ctx.stroke();
      ctx.beginPath(); ctx.moveTo(bx, by);
      ctx.lineTo(bx - hd * ux - 0.5 * hd * uy, by - hd * uy + 0.5 * hd * ux);
      ctx.lineTo(bx - hd * ux + 0.5 * hd * uy, by - hd * uy - 0.5 * hd * ux);
      ctx.closePath(); ctx.fill();
      n++;
    });
    ctx.restore();
    return n;
  }

  function dofList(d, k) {
    var names = d.dof_names || [];
    return d.dofs[k].map(function (v, i) { return (names[i] ? names[i] + " " : "") + num(v, 3); }).join(", ");
  }
  function stepHtml(d, k) {
    if (k === 0) {
      return "<h3>Start</h3><p>" + (d.world ? esc(d.world) + " \u00b7 " : "") + "DOF values (" + dofList(d, 0) +
        "), " + place(d, 0) + ". Press \u25b6 or step through the run.</p>";
    }
    var i = k - 1, tags = [];
    if (d.stuck[i]) tags.push('<span class="tag stuck">stuck</span>');
    if (d.cleared[i]) tags.push('<span class="tag cleared">history cleared after this step</span>');
    if (d.failed[i]) tags.push('<span class="tag failed">no valid action: the hold was played</span>');
    if (d.stroke && i >= d.stroke[0]) {
      tags.push('<span class="tag stroke">stroke, cycle ' + (Math.floor((i - d.stroke[0]) / d.stroke[1]) + 1) +
        " (the criterion's qualifying cycles)</span>");
    }
    var h = "<h3>Step " + k + ": action " + action(d.actions[i]) + "</h3><p>" + tags.join("") +
      " " + ((d.targets || []).length ? place(d, i) + " \u2192 " + place(d, k).replace("(x, y)/a = ", "") :
      toward(d) + " " + signed(d.direction * d.x[i], 4) + " \u2192 " + signed(d.direction * d.x[k], 4) +
      " (this step " + signed(d.direction * (d.x[k] - d.x[i]), 4) + ")") + " \u00b7 DOF values (" +
      dofList(d, k) + ")</p>";
    var step = d.steps[i];
    if (!step) return h;
    h += "<h3>Prompt sent (exact)</h3><pre class=\"prompt\">" + esc(step.prompt || "") + "</pre>";
    h += "<h3>Replies</h3><table><thead><tr><th>#</th><th>reply</th><th>parsed as</th><th>prompt tok</th>" +
      "<th>completion tok</th><th>cost $</th><th>latency s</th><th>HTTP retries</th><th>cache</th><th>finish</th></tr></thead><tbody>";
    (step.attempts || []).forEach(function (a, j) {
      h += "<tr><td>" + (j + 1) + (j ? " (follow-up)" : "") + "</td><td><pre>" + esc(a.text === null ? "" : a.text) +
        "</pre></td><td>" + (a.parsed ? action(a.parsed) : '<span class="error">no valid action</span>') + "</td><td>" +
        num(a.prompt_tokens, 0) + "</td><td>" + num(a.completion_tokens, 0) + "</td><td>" + num(a.cost_usd, 6) +
        "</td><td>" + num(a.latency_s, 3) + "</td><td>" + num(a.retries, 0) + "</td><td>" +
        (a.cache_hit ? "hit" : "") + (a.replayed ? " replayed" : "") + "</td><td>" + esc(a.finish_reason || "") + "</td></tr>";
    });
    h += "</tbody></table>";
    if ((step.attempts || []).length > 1) {
      h += '<p class="note">Follow-ups are the corrective messages sent after a reply that named no valid action.</p>';
    }
    return h;
  }

  document.addEventListener("keydown", function (e) {
    if (!st.data || e.target.tagName === "SELECT" || e.target.tagName === "INPUT") return;
    if (e.key === " ") { e.preventDefault(); st.timer ? pause() : play(); }
    else if (e.key === "ArrowRight") { pause(); show(st.k + 1); }
    else if (e.key === "ArrowLeft") { pause(); show(st.k - 1); }
  });
  document.getElementById("run-list").addEventListener("click", function (e) {
    var tr = e.target.closest("tr[data-i]");
    if (tr) select(parseInt(tr.getAttribute("data-i"), 10));
  });

  buildFilters();
  renderList();
  // Open a run at once: the first LLM run that finished, else the first run.
  var first = runs.filter(function (r) { return r.agent === "llm" && r.status === "done"; })[0] || runs[0];
  var opened = first ? select(first.i) : Promise.resolve();
  // For scripts and tests (the page's own state, read-only apart from these controls).
  window.jswimReport = {
    opened: opened, select: select, play: play, pause: pause,
    step: function () { return st.k; }, drawn: function () { return st.drawn || 0; },
    flowArrows: function () { return st.flowDrawn || 0; },
    data: function () { return st.data; },
    toCanvas: function (x, y) { return [st.X(x), st.Y(y)]; }, steps: function () { return st.data && st.data.actions ? st.data.actions.length : 0; },
    listed: function () { return document.querySelectorAll("#run-list tbody tr").length; },
    finished: D.finished
  };
})();
