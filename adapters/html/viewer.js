// ncperf interactive viewer: draws the embedded tool path with WebGL (a 2-D canvas where
// WebGL is missing), colours it by one of the predicted classes, and links hover, selection,
// the speed plot and the zones table. No network: everything comes from this file.
// Text from inputs is only ever put in place with textContent.
(function () {
  "use strict";

  var META = JSON.parse(document.getElementById("ncperf-meta").textContent);
  var PER_MIN = 60;
  var CELL = 8; // px, picking grid
  var PICK_PX = 7; // hover reach, px
  var t0 = performance.now();

  function $(id) { return document.getElementById(id); }
  function el(tag, cls, text) {
    var e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined && text !== null) e.textContent = String(text);
    return e;
  }
  function fmt(x, d) {
    if (x === null || x === undefined || !isFinite(x)) return "-";
    return Number(x).toLocaleString("en-US", { maximumFractionDigits: d || 0, minimumFractionDigits: d || 0 });
  }
  function status(text, error) {
    var s = $("status");
    s.textContent = text;
    s.className = error ? "error" : "";
  }
  window.ncperfErrors = [];
  window.addEventListener("error", function (e) {
    window.ncperfErrors.push(String(e.message));
    status("error: " + e.message, true);
  });

  // ------------------------------------------------------------------ decoding
  var TYPES = {
    i1: Int8Array, u1: Uint8Array, i2: Int16Array, u2: Uint16Array,
    i4: Int32Array, u4: Uint32Array, f4: Float32Array, f8: Float64Array
  };
  (function checkEndian() {
    if (new Uint8Array(new Uint16Array([1]).buffer)[0] !== 1) throw new Error("big-endian browsers are not supported");
  })();

  function b64bytes(s) {
    if (typeof Uint8Array.fromBase64 === "function") return Uint8Array.fromBase64(s);
    var bin = atob(s), n = bin.length, out = new Uint8Array(n);
    for (var i = 0; i < n; i++) out[i] = bin.charCodeAt(i);
    return out;
  }
  function inflate(bytes) {
    if (typeof DecompressionStream !== "function") {
      return Promise.reject(new Error("this browser cannot decompress the embedded data (no DecompressionStream): use a current Chrome, Edge, Firefox or Safari"));
    }
    var ds = new DecompressionStream("deflate");
    return new Response(new Blob([bytes]).stream().pipeThrough(ds)).arrayBuffer();
  }
  function decode(spec) {
    var node = document.getElementById(spec.id);
    return inflate(b64bytes(node.textContent)).then(function (buf) {
      var raw = new Uint8Array(buf);
      var T = TYPES[spec.dtype];
      var size = T.BYTES_PER_ELEMENT, count = raw.length / size;
      var bytes = raw;
      if (size > 1) { // undo the byte planes
        bytes = new Uint8Array(raw.length);
        for (var b = 0; b < size; b++) {
          var off = b * count;
          for (var i = 0; i < count; i++) bytes[i * size + b] = raw[off + i];
        }
      }
      var arr = new T(bytes.buffer);
      if (spec.delta) {
        var rows = spec.shape.length === 2 ? spec.shape[0] : 1, len = count / rows;
        for (var r = 0; r < rows; r++) {
          var acc = 0, base = r * len;
          for (var k = 0; k < len; k++) { acc = (acc + arr[base + k]) | 0; arr[base + k] = acc; }
        }
      }
      node.textContent = ""; // free the text
      return arr;
    });
  }

  function hexRGB(h) {
    var m = /^#([0-9a-f]{6})$/i.exec(String(h));
    if (!m) return [0, 0, 0];
    var v = parseInt(m[1], 16);
    return [(v >> 16) & 255, (v >> 8) & 255, v & 255];
  }

  // ------------------------------------------------------------------ the data of a program
  function Program(spec, arrays, index) {
    this.spec = spec;
    this.index = index;
    this.n = spec.n;
    for (var k in arrays) this[k] = arrays[k];
    var n = this.n, npts = this.npts;
    var first = new Int32Array(n), last = new Int32Array(n);
    var p = 0;
    for (var i = 0; i < n; i++) {
      var f = npts[i];
      if (f & 128) { first[i] = p; p += 1; } else first[i] = p - 1;
      p += f & 127;
      last[i] = p - 1;
    }
    this.first = first; this.last = last;
    var q = spec.quantum, np = this.pts.length / 3;
    var P = new Float32Array(np * 3);
    for (var j = 0; j < np; j++) {
      P[3 * j] = this.pts[j] * q;
      P[3 * j + 1] = this.pts[np + j] * q;
      P[3 * j + 2] = this.pts[2 * np + j] * q;
    }
    this.P = P;
    this.pts = null;
    var s0 = new Float64Array(n + 1);
    for (i = 0; i < n; i++) s0[i + 1] = s0[i] + this.length[i];
    this.s0 = s0;
    // The junction at the end of each move, if one was reported.
    this.jAt = new Int32Array(n).fill(-1);
    if (this.junction) for (i = 0; i < this.junction.length; i++) this.jAt[this.junction[i]] = i;
    // Segments: feed moves first, then rapids (the rapids toggle draws a prefix).
    var nseg = 0, nfeedseg = 0;
    for (i = 0; i < n; i++) { nseg += last[i] - first[i]; if (this.kind[i] !== 0) nfeedseg += last[i] - first[i]; }
    this.nseg = nseg; this.nfeedseg = nfeedseg;
    var segMove = new Int32Array(nseg), segA = new Int32Array(nseg);
    var a = 0, b = nfeedseg;
    for (i = 0; i < n; i++) {
      var feed = this.kind[i] !== 0;
      for (var v = first[i]; v < last[i]; v++) {
        if (feed) { segMove[a] = i; segA[a++] = v; } else { segMove[b] = i; segA[b++] = v; }
      }
    }
    this.segMove = segMove; this.segA = segA;
    this.lines = null; // the program's lines, split on first use
  }
  Program.prototype.textLine = function (line, move) {
    if (!this.text) return null;
    if (this.origin && this.origin[move] >= 0 && this.spec.origin_files[this.origin[move]]) return null;
    if (!this.lines) this.lines = new TextDecoder("utf-8").decode(this.text).split("\n");
    return line >= 1 && line <= this.lines.length ? this.lines[line - 1] : null;
  };
  Program.prototype.moveAtS = function (s) {
    var lo = 0, hi = this.n - 1;
    while (lo < hi) { var mid = (lo + hi + 1) >> 1; if (this.s0[mid] <= s) lo = mid; else hi = mid - 1; }
    return lo;
  };

  // ------------------------------------------------------------------ colour modes
  var MODES = META.modes.map(function (m) { return m[0]; });
  var state = {
    mode: MODES[0],
    rapids: true,
    sel: null, // {prog, first, last}
    plot: null // {prog, s0, s1}
  };
  if (META.default_mode && MODES.indexOf(META.default_mode) >= 0) state.mode = META.default_mode;

  function classesOf(prog, mode) {
    if (mode === "speed") return prog.sclass;
    if (mode === "junction") return prog.mclass;
    if (mode === "length") return prog.lclass;
    if (mode === "gap") return prog.gclass;
    return prog.mclass;
  }
  function severity(mode, c, ncls) {
    if (c < 0) return 0;
    if (mode === "length") return 1 + (ncls - 1 - c);
    if (mode === "gap") { var mid = (ncls - 1) / 2; return 1 + Math.round(Math.abs(c - mid) * 2); }
    return 1 + c;
  }
  function palette(mode) {
    var c = META.classes[mode] || META.classes.speed;
    return { labels: c.labels, colours: c.colours.map(hexRGB) };
  }

  // ------------------------------------------------------------------ camera (shared)
  var VIEWS = {
    xy: [0, 0], xz: [90, 0], yz: [90, -90], iso: [Math.acos(1 / Math.sqrt(3)) * 180 / Math.PI, 45]
  };
  var cam = { tilt: 0, spin: 0, target: [0, 0, 0], scale: 1 };
  function rotation() {
    var t = cam.tilt * Math.PI / 180, s = cam.spin * Math.PI / 180;
    var ct = Math.cos(t), st = Math.sin(t), cs = Math.cos(s), ss = Math.sin(s);
    // Rx(-tilt) . Rz(spin): rows are the screen right, up and towards-viewer axes.
    return [
      cs, -ss, 0,
      ct * ss, ct * cs, st,
      -st * ss, -st * cs, ct
    ];
  }

  // ------------------------------------------------------------------ one drawing panel
  function View(prog, container) {
    this.prog = prog;
    var wrap = el("div", "panel");
    if (META.panels.length > 1) wrap.appendChild(el("div", "caption", prog.spec.label));
    var stage = el("div", "stage");
    this.canvas = el("canvas", "path");
    this.overlay = el("canvas", "overlay");
    stage.appendChild(this.canvas);
    stage.appendChild(this.overlay);
    wrap.appendChild(stage);
    container.appendChild(wrap);
    this.stage = stage;
    this.grid = null;
    this.colours = null;
    this.gl = null;
    try {
      // Multisampling costs more than the lines themselves where WebGL runs in software
      // (SwiftShader: 1M moves at 1-2 s a frame instead of 0.2-0.4 s): large paths go without.
      var opts = { antialias: prog.nseg < 300000, preserveDrawingBuffer: true };
      this.gl = this.canvas.getContext("webgl", opts) || this.canvas.getContext("experimental-webgl", opts);
    } catch (e) { this.gl = null; }
    if (this.gl) this.initGL(); else this.ctx = this.canvas.getContext("2d");
  }
  View.prototype.size = function () {
    var r = this.stage.getBoundingClientRect(), dpr = window.devicePixelRatio || 1;
    var w = Math.max(1, Math.round(r.width * dpr)), h = Math.max(1, Math.round(r.height * dpr));
    if (this.canvas.width !== w || this.canvas.height !== h) {
      this.canvas.width = w; this.canvas.height = h;
      this.overlay.width = w; this.overlay.height = h;
    }
    this.w = r.width; this.h = r.height; this.dpr = dpr;
  };
  // Screen position (CSS px) of a point relative to the centre.
  View.prototype.project = function (R, x, y, z) {
    var dx = x - cam.target[0], dy = y - cam.target[1], dz = z - cam.target[2];
    return [
      this.w / 2 + cam.scale * (R[0] * dx + R[1] * dy + R[2] * dz),
      this.h / 2 - cam.scale * (R[3] * dx + R[4] * dy + R[5] * dz)
    ];
  };

  var VS = [
    "attribute vec3 p; attribute vec4 c;",
    "uniform mat3 R; uniform vec3 target; uniform vec2 k; uniform float psize;",
    "varying vec3 vc;",
    "void main() {",
    "  vec3 q = R * (p - target);",
    "  gl_Position = vec4(q.x * k.x, q.y * k.y, 0.9 - c.a * 3.0, 1.0);",
    "  gl_PointSize = psize; vc = c.rgb;",
    "}"
  ].join("\n");
  var FS = "precision mediump float; varying vec3 vc; void main() { gl_FragColor = vec4(vc, 1.0); }";

  View.prototype.initGL = function () {
    var gl = this.gl, prog = this.prog;
    function shader(type, src) {
      var s = gl.createShader(type);
      gl.shaderSource(s, src); gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      return s;
    }
    var sp = gl.createProgram();
    gl.attachShader(sp, shader(gl.VERTEX_SHADER, VS));
    gl.attachShader(sp, shader(gl.FRAGMENT_SHADER, FS));
    gl.linkProgram(sp);
    if (!gl.getProgramParameter(sp, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(sp));
    this.sp = sp;
    this.loc = {
      p: gl.getAttribLocation(sp, "p"), c: gl.getAttribLocation(sp, "c"),
      R: gl.getUniformLocation(sp, "R"), target: gl.getUniformLocation(sp, "target"),
      k: gl.getUniformLocation(sp, "k"), psize: gl.getUniformLocation(sp, "psize")
    };
    // Two vertices per segment.
    var nseg = prog.nseg, P = prog.P, pos = new Float32Array(nseg * 6);
    for (var s = 0; s < nseg; s++) {
      var a = prog.segA[s] * 3, o = s * 6;
      pos[o] = P[a]; pos[o + 1] = P[a + 1]; pos[o + 2] = P[a + 2];
      pos[o + 3] = P[a + 3]; pos[o + 4] = P[a + 4]; pos[o + 5] = P[a + 5];
    }
    this.posBuf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.posBuf);
    gl.bufferData(gl.ARRAY_BUFFER, pos, gl.STATIC_DRAW);
    this.colBuf = gl.createBuffer();
    // Junction points (Fig. 11 markers), class 1 and worse.
    var js = [];
    if (prog.junction) for (var i = 0; i < prog.junction.length; i++) if (prog.jclass[i] >= 1) js.push(i);
    this.nj = js.length;
    var jpos = new Float32Array(js.length * 3), jcol = new Uint8Array(js.length * 4);
    var pal = palette("junction");
    for (i = 0; i < js.length; i++) {
      var m = prog.junction[js[i]], e = prog.last[m] * 3, c = prog.jclass[js[i]];
      jpos[3 * i] = P[e]; jpos[3 * i + 1] = P[e + 1]; jpos[3 * i + 2] = P[e + 2];
      var rgb = pal.colours[Math.min(c, pal.colours.length - 1)];
      jcol[4 * i] = rgb[0]; jcol[4 * i + 1] = rgb[1]; jcol[4 * i + 2] = rgb[2]; jcol[4 * i + 3] = 40 + c;
    }
    this.jPosBuf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.jPosBuf);
    gl.bufferData(gl.ARRAY_BUFFER, jpos, gl.STATIC_DRAW);
    this.jColBuf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.jColBuf);
    gl.bufferData(gl.ARRAY_BUFFER, jcol, gl.STATIC_DRAW);
  };

  // Per-segment colour and severity of the current mode; uploaded to the GPU.
  View.prototype.recolour = function () {
    var prog = this.prog, mode = state.mode, pal = palette(mode), ncls = pal.colours.length;
    var cls = classesOf(prog, mode) || prog.mclass;
    var rapid = hexRGB(META.rapid_colour), nseg = prog.nseg;
    var col = new Uint8Array(nseg * 8);
    this.sev = new Uint8Array(nseg);
    for (var s = 0; s < nseg; s++) {
      var m = prog.segMove[s], c = prog.kind[m] === 0 ? -1 : cls[m];
      var rgb = c >= 0 ? pal.colours[Math.min(c, ncls - 1)] : rapid;
      var sv = c >= 0 ? severity(mode, c, ncls) : 0;
      this.sev[s] = sv;
      var o = s * 8;
      col[o] = col[o + 4] = rgb[0]; col[o + 1] = col[o + 5] = rgb[1]; col[o + 2] = col[o + 6] = rgb[2];
      col[o + 3] = col[o + 7] = sv;
    }
    this.col = col;
    if (this.gl) {
      var gl = this.gl;
      gl.bindBuffer(gl.ARRAY_BUFFER, this.colBuf);
      gl.bufferData(gl.ARRAY_BUFFER, col, gl.STATIC_DRAW);
    }
  };

  View.prototype.draw = function () {
    this.size();
    var R = rotation(), prog = this.prog;
    var nseg = state.rapids ? prog.nseg : prog.nfeedseg;
    if (this.gl) {
      var gl = this.gl, L = this.loc;
      gl.viewport(0, 0, this.canvas.width, this.canvas.height);
      gl.clearColor(1, 1, 1, 1);
      gl.clearDepth(1);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      gl.enable(gl.DEPTH_TEST);
      gl.depthFunc(gl.LEQUAL);
      gl.useProgram(this.sp);
      // mat3 uniforms are column-major: upload the transpose of the row-major R.
      gl.uniformMatrix3fv(L.R, false, new Float32Array([R[0], R[3], R[6], R[1], R[4], R[7], R[2], R[5], R[8]]));
      gl.uniform3f(L.target, cam.target[0], cam.target[1], cam.target[2]);
      gl.uniform2f(L.k, 2 * cam.scale / this.w, 2 * cam.scale / this.h);
      gl.uniform1f(L.psize, 5 * this.dpr);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.posBuf);
      gl.enableVertexAttribArray(L.p);
      gl.vertexAttribPointer(L.p, 3, gl.FLOAT, false, 0, 0);
      gl.bindBuffer(gl.ARRAY_BUFFER, this.colBuf);
      gl.enableVertexAttribArray(L.c);
      gl.vertexAttribPointer(L.c, 4, gl.UNSIGNED_BYTE, true, 0, 0);
      gl.drawArrays(gl.LINES, 0, nseg * 2);
      if (state.mode === "junction" && this.nj) {
        gl.bindBuffer(gl.ARRAY_BUFFER, this.jPosBuf);
        gl.vertexAttribPointer(L.p, 3, gl.FLOAT, false, 0, 0);
        gl.bindBuffer(gl.ARRAY_BUFFER, this.jColBuf);
        gl.vertexAttribPointer(L.c, 4, gl.UNSIGNED_BYTE, true, 0, 0);
        gl.drawArrays(gl.POINTS, 0, this.nj);
      }
    } else {
      this.draw2d(R, nseg);
    }
    this.drawOverlay();
  };

  // The fallback: one path per colour, the worst drawn last.
  View.prototype.draw2d = function (R, nseg) {
    var ctx = this.ctx, prog = this.prog, P = prog.P, dpr = this.dpr;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.fillStyle = "#fff";
    ctx.fillRect(0, 0, this.w, this.h);
    ctx.lineWidth = 1;
    var bySev = {};
    for (var s = 0; s < nseg; s++) { var k = this.sev[s]; (bySev[k] = bySev[k] || []).push(s); }
    var keys = Object.keys(bySev).map(Number).sort(function (a, b) { return a - b; });
    for (var i = 0; i < keys.length; i++) {
      var list = bySev[keys[i]], byCol = {};
      for (var j = 0; j < list.length; j++) {
        var o = list[j] * 8, key = "rgb(" + this.col[o] + "," + this.col[o + 1] + "," + this.col[o + 2] + ")";
        (byCol[key] = byCol[key] || []).push(list[j]);
      }
      for (var colour in byCol) {
        ctx.strokeStyle = colour;
        ctx.beginPath();
        var segs = byCol[colour];
        for (j = 0; j < segs.length; j++) {
          var a = prog.segA[segs[j]] * 3;
          var p0 = this.project(R, P[a], P[a + 1], P[a + 2]), p1 = this.project(R, P[a + 3], P[a + 4], P[a + 5]);
          ctx.moveTo(p0[0], p0[1]); ctx.lineTo(p1[0], p1[1]);
        }
        ctx.stroke();
      }
    }
    if (state.mode === "junction" && prog.junction) {
      var pal = palette("junction");
      for (i = 0; i < prog.junction.length; i++) {
        var c = prog.jclass[i];
        if (c < 1) continue;
        var e = prog.last[prog.junction[i]] * 3, q = this.project(R, P[e], P[e + 1], P[e + 2]);
        var rgb = pal.colours[Math.min(c, pal.colours.length - 1)];
        ctx.fillStyle = "rgb(" + rgb.join(",") + ")";
        ctx.fillRect(q[0] - 2.5, q[1] - 2.5, 5, 5);
      }
    }
  };

  // Selection and hover highlight, zone rings, on the transparent canvas above.
  View.prototype.drawOverlay = function () {
    var ctx = this.overlay.getContext("2d"), dpr = this.dpr, prog = this.prog, P = prog.P;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, this.w, this.h);
    var R = rotation(), self = this;
    function stroke(first, last, colour, width) {
      var a = prog.first[first], b = prog.last[last];
      if (b - a > 200000) return;
      ctx.strokeStyle = colour; ctx.lineWidth = width; ctx.lineJoin = "round"; ctx.lineCap = "round";
      ctx.beginPath();
      for (var v = a; v <= b; v++) {
        var q = self.project(R, P[3 * v], P[3 * v + 1], P[3 * v + 2]);
        if (v === a) ctx.moveTo(q[0], q[1]); else ctx.lineTo(q[0], q[1]);
      }
      ctx.stroke();
    }
    if (state.sel && state.sel.prog === prog.index) {
      stroke(state.sel.first, state.sel.last, "rgba(0,0,0,0.85)", 6);
      stroke(state.sel.first, state.sel.last, "#00e5ff", 2.5);
    }
    if (this.hover !== undefined && this.hover !== null) stroke(this.hover, this.hover, "rgba(0,0,0,0.7)", 4);
    // Zone rings: zones within a ring's width of each other share one, labelled "1, 3".
    var zs = prog.spec.zones || [], rings = [];
    for (var i = 0; i < zs.length && i < 10; i++) {
      var z = zs[i], q = this.project(R, z.point[0], z.point[1], z.point[2]), ring = null;
      for (var r = 0; r < rings.length; r++) {
        if (Math.abs(rings[r].x - q[0]) < 14 && Math.abs(rings[r].y - q[1]) < 14) { ring = rings[r]; break; }
      }
      if (ring) ring.ranks.push(z.rank); else rings.push({ x: q[0], y: q[1], ranks: [z.rank] });
    }
    ctx.font = "bold 12px sans-serif";
    for (r = 0; r < rings.length; r++) {
      var g = rings[r], label = g.ranks.join(", ");
      ctx.strokeStyle = "#000"; ctx.lineWidth = 1.5;
      ctx.beginPath(); ctx.arc(g.x, g.y, 7, 0, 2 * Math.PI); ctx.stroke();
      ctx.lineWidth = 3; ctx.strokeStyle = "#fff";
      ctx.strokeText(label, g.x + 8, g.y - 8);
      ctx.fillStyle = "#000"; ctx.fillText(label, g.x + 8, g.y - 8);
    }
  };

  // ------------------------------------------------------------------ picking grid
  // Built on the first hover after the view changed: every drawn segment in the screen cells
  // it crosses (CSR arrays), then the nearest segment within PICK_PX of the pointer.
  View.prototype.buildGrid = function () {
    var prog = this.prog, P = prog.P, R = rotation();
    var nseg = state.rapids ? prog.nseg : prog.nfeedseg;
    var gw = Math.ceil(this.w / CELL) + 1, gh = Math.ceil(this.h / CELL) + 1;
    var np = P.length / 3, sx = new Float32Array(np), sy = new Float32Array(np);
    var cx = this.w / 2, cy = this.h / 2, k = cam.scale, t = cam.target;
    for (var v = 0; v < np; v++) {
      var dx = P[3 * v] - t[0], dy = P[3 * v + 1] - t[1], dz = P[3 * v + 2] - t[2];
      sx[v] = cx + k * (R[0] * dx + R[1] * dy + R[2] * dz);
      sy[v] = cy - k * (R[3] * dx + R[4] * dy + R[5] * dz);
    }
    var count = new Int32Array(gw * gh + 1);
    function walk(s, fn) {
      var a = prog.segA[s], x0 = sx[a], y0 = sy[a], x1 = sx[a + 1], y1 = sy[a + 1];
      if ((x0 < -CELL && x1 < -CELL) || (y0 < -CELL && y1 < -CELL)) return;
      if ((x0 > gw * CELL && x1 > gw * CELL) || (y0 > gh * CELL && y1 > gh * CELL)) return;
      var len = Math.max(Math.abs(x1 - x0), Math.abs(y1 - y0));
      var steps = Math.min(Math.ceil(len / (CELL / 2)), 4096), last = -1;
      for (var i = 0; i <= steps; i++) {
        var f = steps ? i / steps : 0, x = x0 + (x1 - x0) * f, y = y0 + (y1 - y0) * f;
        var gx = Math.floor(x / CELL), gy = Math.floor(y / CELL);
        if (gx < 0 || gy < 0 || gx >= gw || gy >= gh) continue;
        var c = gy * gw + gx;
        if (c !== last) { fn(c); last = c; }
      }
    }
    for (var s = 0; s < nseg; s++) walk(s, function (c) { count[c + 1]++; });
    for (var c = 0; c < gw * gh; c++) count[c + 1] += count[c];
    var fill = count.slice(0, gw * gh), items = new Int32Array(count[gw * gh]);
    for (s = 0; s < nseg; s++) walk(s, function (c) { items[fill[c]++] = s; });
    this.grid = { gw: gw, gh: gh, start: count, items: items, sx: sx, sy: sy };
  };
  View.prototype.pick = function (x, y) {
    if (!this.grid) this.buildGrid();
    var G = this.grid, prog = this.prog, best = -1, bestD = PICK_PX * PICK_PX, bestSev = -1;
    var g0 = Math.floor((x - PICK_PX) / CELL), g1 = Math.floor((x + PICK_PX) / CELL);
    var h0 = Math.floor((y - PICK_PX) / CELL), h1 = Math.floor((y + PICK_PX) / CELL);
    for (var gy = Math.max(h0, 0); gy <= Math.min(h1, G.gh - 1); gy++) {
      for (var gx = Math.max(g0, 0); gx <= Math.min(g1, G.gw - 1); gx++) {
        var c = gy * G.gw + gx;
        for (var i = G.start[c]; i < G.start[c + 1]; i++) {
          var s = G.items[i], a = prog.segA[s];
          var x0 = G.sx[a], y0 = G.sy[a], dx = G.sx[a + 1] - x0, dy = G.sy[a + 1] - y0;
          var l2 = dx * dx + dy * dy, f = l2 > 0 ? ((x - x0) * dx + (y - y0) * dy) / l2 : 0;
          f = f < 0 ? 0 : f > 1 ? 1 : f;
          var ex = x0 + f * dx - x, ey = y0 + f * dy - y, d = ex * ex + ey * ey;
          var sv = this.sev ? this.sev[s] : 0;
          if (d < bestD - 0.5 || (d <= bestD + 0.5 && sv > bestSev)) { bestD = d; best = s; bestSev = sv; }
        }
      }
    }
    return best < 0 ? null : prog.segMove[best];
  };

  // ------------------------------------------------------------------ text of a move
  function describe(prog, i) {
    var out = [], spec = prog.spec, line = prog.line[i];
    var head = (META.panels.length > 1 ? spec.label + ": " : "") + "line " + line;
    if (prog.origin && prog.origin[i] >= 0) {
      var o = prog.origin[i];
      head += " (run by " + spec.origins[o] + (spec.origin_files[o] ? ", in " + spec.origin_files[o] : "") + ")";
    }
    var kind = ["rapid", "line", "arc"][prog.kind[i]] || "move";
    out.push([head + " \u00b7 " + kind + " \u00b7 move " + (i + 1) + " of " + prog.n, "head"]);
    var text = prog.textLine(line, i);
    if (text !== null) out.push([text, "src"]);
    if (prog.kind[i] === 0) {
      out.push(["rapid, " + fmt(prog.length[i], 3) + " mm", ""]);
      return out;
    }
    var F = prog.feed[i];
    var pred = prog.share ? prog.share[i] / 65535 : null;
    out.push(["programmed F " + fmt(F) + " mm/min" + (pred !== null ? " \u00b7 predicted mean " + fmt(F * pred) + " mm/min (" + fmt(100 * pred) + " % of F)" : ""), ""]);
    out.push(["length " + fmt(prog.length[i], 3) + " mm", "k"]);
    if (prog.elim && prog.elim[i] >= 0) {
      out.push(["block capped at " + fmt(prog.efeed[i]) + " mm/min by " + spec.names[prog.elim[i]], ""]);
    }
    var ends = [[i - 1, "start"], [i, "end"]];
    for (var e = 0; e < 2; e++) {
      var m = ends[e][0];
      if (m < 0 || prog.jAt[m] < 0) continue;
      var j = prog.jAt[m], cls = prog.jclass[j];
      var name = prog.jname[j] >= 0 ? spec.names[prog.jname[j]] : "programmed feed";
      var red = Math.round(100 * (1 - prog.jfeed[j] / Math.min(F, prog.feed[Math.min(m + 1, prog.n - 1)] || F)));
      out.push([ends[e][1] + ": " + fmt(prog.jfeed[j]) + " mm/min at the junction (" + (red > 0 ? "-" + red + " %" : "at F") + ", " + name + ")" + (cls >= 1 ? "" : ""), ""]);
    }
    if (prog.gap) {
      var g = prog.gap[i];
      out.push([isFinite(g) ? "measured - predicted: " + (g >= 0 ? "+" : "") + fmt(100 * g) + " % of F" : "not in the trace", ""]);
    }
    return out;
  }
  function fillInfo(node, lines) {
    node.textContent = "";
    for (var k = 0; k < lines.length; k++) {
      var d = el("div", lines[k][1] === "head" ? "" : lines[k][1], lines[k][0]);
      if (lines[k][1] === "head") d.style.fontWeight = "bold";
      node.appendChild(d);
    }
  }

  // ------------------------------------------------------------------ speed plot
  function speedPoints(prog, i, out) {
    var s0 = prog.s0[i], L = prog.length[i];
    if (prog.block_speed) {
      out.push(s0, prog.block_speed[i], s0 + L, prog.block_speed[i]);
      return;
    }
    if (!prog.v) return;
    var n = prog.n, k = prog.spec.vmax / 65535;
    var ve = prog.v[i] * k, vp = prog.v[n + i] * k, vx = prog.v[2 * n + i] * k;
    var f = prog.frac, h0 = f[i] / 255, up = f[n + i] / 255, dn = f[2 * n + i] / 255, h1 = f[3 * n + i] / 255;
    out.push(s0, ve, s0 + h0 * L, ve);
    // Constant acceleration: v^2 grows linearly with s over a ramp.
    var j;
    for (j = 1; j <= 6; j++) {
      var t = j / 6;
      out.push(s0 + (h0 + (up - h0) * t) * L, Math.sqrt(ve * ve + (vp * vp - ve * ve) * t));
    }
    for (j = 0; j <= 6; j++) {
      t = j / 6;
      out.push(s0 + (dn + (h1 - dn) * t) * L, Math.sqrt(vp * vp + (vx * vx - vp * vp) * t));
    }
    out.push(s0 + L, vx);
  }
  function drawPlot() {
    var cv = $("plot"), r = cv.getBoundingClientRect(), dpr = window.devicePixelRatio || 1;
    cv.width = Math.max(1, Math.round(r.width * dpr)); cv.height = Math.max(1, Math.round(r.height * dpr));
    var ctx = cv.getContext("2d"), W = r.width, H = r.height;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, W, H);
    var pl = state.plot;
    if (!pl) { $("plotnote").textContent = "(click the path)"; return; }
    var prog = PROGRAMS[pl.prog];
    if (!prog.v && !prog.block_speed) { $("plotnote").textContent = "(no feed profile in this page)"; return; }
    var L = 48, B = 22, T = 8, Rr = 8, pw = W - L - Rr, ph = H - B - T;
    var a = prog.moveAtS(pl.s0), b = prog.moveAtS(pl.s1);
    if (b - a > 20000) b = a + 20000;
    var pred = [], feed = [], vmax = 1;
    for (var i = a; i <= b; i++) {
      // Rapids are left out (a gap in the curve): their speed would set the scale.
      if (prog.kind[i] === 0) { pred.push(NaN, NaN); continue; }
      speedPoints(prog, i, pred);
      if (prog.kind[i] !== 0) { feed.push(prog.s0[i], prog.feed[i], prog.s0[i + 1], prog.feed[i]); vmax = Math.max(vmax, prog.feed[i]); }
    }
    for (i = 1; i < pred.length; i += 2) if (pred[i] > vmax) vmax = pred[i];
    var meas = [];
    if (prog.measured) {
      for (var t = 0; t < prog.measured.length; t++) {
        var M = prog.measured[t], lo = 0, hi = M.s.length;
        while (lo < hi) { var mid = (lo + hi) >> 1; if (M.s[mid] < pl.s0) lo = mid + 1; else hi = mid; }
        var pts = [];
        for (var q = lo; q < M.s.length && M.s[q] <= pl.s1; q++) { pts.push(M.s[q], M.v[q]); vmax = Math.max(vmax, M.v[q]); }
        meas.push(pts);
      }
    }
    vmax *= 1.08;
    var span = Math.max(pl.s1 - pl.s0, 1e-9);
    function X(s) { return L + (s - pl.s0) / span * pw; }
    function Y(v) { return T + ph - v / vmax * ph; }
    ctx.strokeStyle = "#ccc"; ctx.lineWidth = 1; ctx.strokeRect(L, T, pw, ph);
    if (state.sel && state.sel.prog === pl.prog) {
      ctx.fillStyle = "rgba(0,229,255,0.25)";
      var xa = X(prog.s0[state.sel.first]), xb = X(prog.s0[state.sel.last + 1]);
      ctx.fillRect(xa, T, Math.max(xb - xa, 2), ph);
    }
    ctx.save(); ctx.beginPath(); ctx.rect(L, T, pw, ph); ctx.clip();
    function line(arr, colour, width, dash) {
      ctx.strokeStyle = colour; ctx.lineWidth = width; ctx.setLineDash(dash || []);
      ctx.beginPath();
      var up = true;
      for (var k = 0; k < arr.length; k += 2) {
        if (arr[k] !== arr[k]) { up = true; continue; } // NaN: a break
        if (up) ctx.moveTo(X(arr[k]), Y(arr[k + 1])); else ctx.lineTo(X(arr[k]), Y(arr[k + 1]));
        up = false;
      }
      ctx.stroke(); ctx.setLineDash([]);
    }
    line(feed, "#999", 1, [4, 3]);
    for (t = 0; t < meas.length; t++) line(meas[t], "#000", 1.2);
    line(pred, "#d73027", 1.5);
    ctx.restore();
    ctx.fillStyle = "#333"; ctx.font = "11px sans-serif";
    ctx.textAlign = "right";
    ctx.fillText(fmt(vmax / 1.08), L - 4, Y(vmax / 1.08) + 4);
    ctx.fillText("0", L - 4, T + ph);
    ctx.textAlign = "left"; ctx.fillText(fmt(pl.s0, 1) + " mm", L, H - 6);
    ctx.textAlign = "right"; ctx.fillText(fmt(pl.s1, 1) + " mm", L + pw, H - 6);
    ctx.textAlign = "left";
    $("plotnote").textContent = "(mm/min over mm; red predicted, dashed F" + (meas.length ? ", black measured" : "") + "; wheel: zoom, click: select)";
    drawPlot.map = { X0: L, pw: pw, s0: pl.s0, span: span, prog: pl.prog };
  }
  function plotAround(pi, first, last, width) {
    var prog = PROGRAMS[pi], s0 = prog.s0[first], s1 = prog.s0[last + 1];
    var total = prog.s0[prog.n];
    var w = width || (state.plot && state.plot.prog === pi ? state.plot.s1 - state.plot.s0 : Math.min(total, Math.max(5, Math.min(500, total / 20))));
    w = Math.max(w, (s1 - s0) * 1.2);
    var c = (s0 + s1) / 2;
    state.plot = { prog: pi, s0: Math.max(0, c - w / 2), s1: Math.min(total, c + w / 2) };
    drawPlot();
  }

  // ------------------------------------------------------------------ page
  var PROGRAMS = [], VIEWS_ = [];
  function redraw() { for (var i = 0; i < VIEWS_.length; i++) { VIEWS_[i].grid = null; VIEWS_[i].draw(); } }
  var pending = false;
  function schedule() {
    if (pending) return;
    pending = true;
    requestAnimationFrame(function () { pending = false; redraw(); });
  }

  function fit(box, margin) {
    // box: [lo, hi] relative to the centre; fit it in the smallest panel, with ``margin``
    // times its size around it (a zone), at least a fifth of its larger side across.
    var R = rotation(), lo = box[0], hi = box[1];
    var umin = Infinity, umax = -Infinity, vmin = Infinity, vmax = -Infinity;
    for (var c = 0; c < 8; c++) {
      var x = c & 1 ? hi[0] : lo[0], y = c & 2 ? hi[1] : lo[1], z = c & 4 ? hi[2] : lo[2];
      var u = R[0] * x + R[1] * y + R[2] * z, v = R[3] * x + R[4] * y + R[5] * z;
      umin = Math.min(umin, u); umax = Math.max(umax, u); vmin = Math.min(vmin, v); vmax = Math.max(vmax, v);
    }
    var w = Infinity, h = Infinity;
    for (var i = 0; i < VIEWS_.length; i++) { VIEWS_[i].size(); w = Math.min(w, VIEWS_[i].w); h = Math.min(h, VIEWS_[i].h); }
    var du = Math.max(umax - umin, 1e-6), dv = Math.max(vmax - vmin, 1e-6);
    if (margin) {
      var side = Math.max(du, dv, 0.5);
      du = Math.max(du, side / 5) * (1 + 2 * margin); dv = Math.max(dv, side / 5) * (1 + 2 * margin);
    }
    cam.scale = Math.min((w - 40) / du, (h - 40) / dv);
    var cu = (umin + umax) / 2, cv = (vmin + vmax) / 2, cz = (lo[2] + hi[2]) / 2;
    // The point whose screen coordinates are (cu, cv): solve with the depth axis at cz's.
    var d = R[6] * (lo[0] + hi[0]) / 2 + R[7] * (lo[1] + hi[1]) / 2 + R[8] * cz;
    cam.target = [R[0] * cu + R[3] * cv + R[6] * d, R[1] * cu + R[4] * cv + R[7] * d, R[2] * cu + R[5] * cv + R[8] * d];
  }
  function wholeBox() {
    var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (var i = 0; i < PROGRAMS.length; i++) {
      var s = PROGRAMS[i].spec;
      for (var k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], s.lo[k]); hi[k] = Math.max(hi[k], s.hi[k]); }
    }
    return [lo, hi];
  }
  function setView(name) {
    cam.tilt = VIEWS[name][0]; cam.spin = VIEWS[name][1];
    var bs = $("views").children;
    for (var i = 0; i < bs.length; i++) bs[i].className = bs[i].dataset.view === name ? "on" : "";
    fit(wholeBox());
    schedule();
  }

  function legend() {
    var box = $("legend"), mode = state.mode, pal = palette(mode);
    box.textContent = "";
    box.className = "box";
    var title = META.modes.filter(function (m) { return m[0] === mode; })[0][1];
    box.appendChild(el("div", "title", title));
    var counts = new Array(pal.labels.length).fill(0), rapids = 0, jcounts = new Array(pal.labels.length).fill(0);
    for (var p = 0; p < PROGRAMS.length; p++) {
      var prog = PROGRAMS[p], cls = classesOf(prog, mode) || prog.mclass;
      for (var i = 0; i < prog.n; i++) {
        if (prog.kind[i] === 0) rapids++;
        else if (cls[i] >= 0 && cls[i] < counts.length) counts[cls[i]]++;
      }
      if (mode === "junction" && prog.junction) for (i = 0; i < prog.jclass.length; i++) if (prog.jclass[i] >= 1) jcounts[prog.jclass[i]]++;
    }
    for (var c = 0; c < pal.labels.length; c++) {
      var row = el("div", "row"), sw = el("span", "sw");
      sw.style.background = "rgb(" + pal.colours[c].join(",") + ")";
      row.appendChild(sw);
      row.appendChild(el("span", "", pal.labels[c]));
      var txt = fmt(counts[c]) + " blocks" + (mode === "junction" && c >= 1 ? ", " + fmt(jcounts[c]) + " junctions" : "");
      row.appendChild(el("span", "count", txt));
      box.appendChild(row);
    }
    var r = el("div", "row"), s2 = el("span", "sw");
    s2.style.background = META.rapid_colour;
    r.appendChild(s2); r.appendChild(el("span", "", mode === "gap" ? "rapid, or not in the trace" : "rapid (G0)"));
    r.appendChild(el("span", "count", fmt(rapids) + " moves"));
    box.appendChild(r);
    if (mode === "junction") box.appendChild(el("div", "k", "dots: junctions 10 % or more below F, by their own reduction"));
    if (mode === "speed") box.appendChild(el("div", "k", "each block by its mean predicted speed over F: braking, slow crossing and re-acceleration included"));
  }

  function zonesTable() {
    var t = $("zones");
    t.textContent = "";
    var rows = [];
    for (var p = 0; p < PROGRAMS.length; p++) {
      var zs = PROGRAMS[p].spec.zones || [];
      for (var i = 0; i < zs.length; i++) rows.push([p, zs[i]]);
    }
    if (!rows.length) { $("zonehead").textContent = "No zones below 90 % of F"; return; }
    var diag = META.kind === "diagnose";
    var head = el("thead"), hr = el("tr");
    var cols = (PROGRAMS.length > 1 ? ["program"] : []).concat(["#", "lines", diag ? "measured - predicted time (s)" : "time lost (s)", diag ? "what is there" : "cause"]);
    cols.forEach(function (c) { hr.appendChild(el("th", "", c)); });
    head.appendChild(hr); t.appendChild(head);
    var body = el("tbody");
    rows.forEach(function (pz) {
      var z = pz[1], tr = el("tr");
      if (PROGRAMS.length > 1) tr.appendChild(el("td", "", PROGRAMS[pz[0]].spec.label));
      tr.appendChild(el("td", "num", z.rank));
      tr.appendChild(el("td", "", z.lines + (z.origin ? " (run by " + z.origin + ")" : "")));
      tr.appendChild(el("td", "num", (diag && z.time_lost > 0 ? "+" : "") + fmt(z.time_lost, 3)));
      tr.appendChild(el("td", "", z.cause));
      tr.addEventListener("click", function () {
        var bs = body.children;
        for (var k = 0; k < bs.length; k++) bs[k].className = "";
        tr.className = "on";
        zoomTo(pz[0], z);
      });
      body.appendChild(tr);
    });
    t.appendChild(body);
  }
  // Zoom to a zone: its worst point, with its length around it; select its moves.
  function zoomTo(pi, z) {
    var prog = PROGRAMS[pi], h = Math.max(z.size / 2, 0.5), c = z.point;
    var a = Math.max(0, Math.min(z.first, prog.n - 1)), b = Math.max(a, Math.min(z.last, prog.n - 1));
    fit([[c[0] - h, c[1] - h, c[2] - h], [c[0] + h, c[1] + h, c[2] + h]], 0.2);
    select(pi, a, b);
    plotAround(pi, a, b, Math.max((prog.s0[b + 1] - prog.s0[a]) * 2, 2));
    schedule();
  }
  function select(pi, a, b) {
    state.sel = { prog: pi, first: a, last: b };
    fillInfo($("info"), describe(PROGRAMS[pi], a).concat(b > a ? [["selected: moves " + (a + 1) + "-" + (b + 1), "k"]] : []));
    for (var i = 0; i < VIEWS_.length; i++) VIEWS_[i].drawOverlay();
  }

  function rankingTable() {
    var t = $("ranking");
    if (!META.table || !META.table.length) { t.style.display = "none"; return; }
    var head = el("thead"), hr = el("tr");
    META.table[0].forEach(function (c) { hr.appendChild(el("th", "", c)); });
    head.appendChild(hr); t.appendChild(head);
    var body = el("tbody");
    META.table.slice(1).forEach(function (row) {
      var tr = el("tr");
      row.forEach(function (c, k) { tr.appendChild(el("td", k > 1 && /^[-+0-9.,: %s]+$/.test(c) ? "num" : "", c)); });
      body.appendChild(tr);
    });
    t.appendChild(body);
  }

  function wire(view) {
    var cv = view.canvas, drag = null, tip = $("tip");
    cv.addEventListener("contextmenu", function (e) { e.preventDefault(); });
    cv.addEventListener("mousedown", function (e) {
      drag = { x: e.clientX, y: e.clientY, rotate: e.button === 2 || e.shiftKey, moved: false };
    });
    window.addEventListener("mouseup", function (e) {
      if (drag && !drag.moved && e.target === cv) {
        var r = cv.getBoundingClientRect(), m = view.pick(e.clientX - r.left, e.clientY - r.top);
        if (m !== null) { select(view.prog.index, m, m); plotAround(view.prog.index, m, m); }
      }
      drag = null;
    });
    window.addEventListener("mousemove", function (e) {
      if (!drag) return;
      var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      if (!drag.moved && Math.abs(dx) + Math.abs(dy) < 3) return;
      drag.moved = true; drag.x = e.clientX; drag.y = e.clientY;
      var R = rotation();
      if (drag.rotate) {
        cam.spin += dx * 0.4; cam.tilt = Math.max(0, Math.min(180, cam.tilt - dy * 0.4));
      } else {
        var du = -dx / cam.scale, dv = dy / cam.scale;
        for (var k = 0; k < 3; k++) cam.target[k] += R[k] * du + R[3 + k] * dv;
      }
      tip.style.display = "none";
      schedule();
    });
    cv.addEventListener("wheel", function (e) {
      e.preventDefault();
      var r = cv.getBoundingClientRect(), R = rotation();
      var mx = e.clientX - r.left - view.w / 2, my = -(e.clientY - r.top - view.h / 2);
      var f = Math.exp(-e.deltaY * 0.0015), old = cam.scale;
      cam.scale *= f;
      // keep the point under the pointer in place
      var du = mx / old - mx / cam.scale, dv = my / old - my / cam.scale;
      for (var k = 0; k < 3; k++) cam.target[k] += R[k] * du + R[3 + k] * dv;
      schedule();
    }, { passive: false });
    cv.addEventListener("mousemove", function (e) {
      if (drag && drag.moved) return;
      var r = cv.getBoundingClientRect(), m = view.pick(e.clientX - r.left, e.clientY - r.top);
      if (m === null) { tip.style.display = "none"; if (view.hover !== null) { view.hover = null; view.drawOverlay(); } return; }
      view.hover = m;
      view.drawOverlay();
      tip.textContent = describe(view.prog, m).map(function (l) { return l[0]; }).join("\n");
      tip.style.display = "block";
      tip.style.left = Math.min(e.clientX + 14, window.innerWidth - 380) + "px";
      tip.style.top = (e.clientY + 14) + "px";
    });
    cv.addEventListener("mouseleave", function () { tip.style.display = "none"; view.hover = null; view.drawOverlay(); });
  }

  function setup() {
    $("title").textContent = META.title;
    document.title = META.title;
    var vb = $("views");
    ["xy", "xz", "yz", "iso"].forEach(function (v) {
      var b = el("button", "", v === "iso" ? "iso" : v.toUpperCase());
      b.type = "button"; b.dataset.view = v;
      b.addEventListener("click", function () { setView(v); });
      vb.appendChild(b);
    });
    var sel = $("mode");
    META.modes.forEach(function (m) { var o = el("option", "", m[1]); o.value = m[0]; sel.appendChild(o); });
    sel.value = state.mode;
    sel.addEventListener("change", function () {
      state.mode = sel.value;
      for (var i = 0; i < VIEWS_.length; i++) VIEWS_[i].recolour();
      legend(); schedule();
    });
    $("rapids").addEventListener("change", function (e) { state.rapids = e.target.checked; schedule(); });
    $("reset").addEventListener("click", function () { fit(wholeBox()); schedule(); });
    if (META.verdict) $("verdict").textContent = META.verdict;
    rankingTable();
    var plot = $("plot");
    plot.addEventListener("wheel", function (e) {
      if (!state.plot) return;
      e.preventDefault();
      var pl = state.plot, mp = drawPlot.map, r = plot.getBoundingClientRect();
      var s = mp.s0 + (e.clientX - r.left - mp.X0) / mp.pw * mp.span, f = Math.exp(e.deltaY * 0.0015);
      var total = PROGRAMS[pl.prog].s0[PROGRAMS[pl.prog].n];
      pl.s0 = Math.max(0, s - (s - pl.s0) * f); pl.s1 = Math.min(total, s + (pl.s1 - s) * f);
      drawPlot();
    }, { passive: false });
    plot.addEventListener("click", function (e) {
      if (!state.plot || !drawPlot.map) return;
      var mp = drawPlot.map, r = plot.getBoundingClientRect();
      var s = mp.s0 + (e.clientX - r.left - mp.X0) / mp.pw * mp.span, m = PROGRAMS[mp.prog].moveAtS(s);
      select(mp.prog, m, m); drawPlot();
    });
    window.addEventListener("resize", function () { schedule(); drawPlot(); });
  }

  function start() {
    setup();
    var jobs = META.panels.map(function (spec) {
      var keys = ["npts", "pts", "kind", "line", "feed", "length", "mclass", "lclass", "share", "sclass",
        "elim", "efeed", "junction", "jclass", "jfeed", "jname", "v", "frac", "origin", "text", "gap", "gclass", "block_speed"];
      var have = keys.filter(function (k) { return spec[k]; });
      var mjobs = (spec.measured || []).map(function (m) {
        return Promise.all([decode(m.s), decode(m.v)]).then(function (a) { return { label: m.label, s: a[0], v: a[1] }; });
      });
      return Promise.all([Promise.all(have.map(function (k) { return decode(spec[k]); })), Promise.all(mjobs)]).then(function (res) {
        var arrays = {};
        have.forEach(function (k, i) { arrays[k] = res[0][i]; });
        if (res[1].length) arrays.measured = res[1];
        return arrays;
      });
    });
    return Promise.all(jobs).then(function (all) {
      var container = $("panels");
      for (var i = 0; i < all.length; i++) {
        var prog = new Program(META.panels[i], all[i], i);
        PROGRAMS.push(prog);
        var v = new View(prog, container);
        v.recolour();
        VIEWS_.push(v);
        wire(v);
      }
      legend();
      zonesTable();
      setView(META.view in VIEWS ? META.view : "xy");
      redraw();
      drawPlot();
      var n = PROGRAMS.reduce(function (a, p) { return a + p.n; }, 0);
      var notes = PROGRAMS.map(function (p) { return p.spec.text_note; }).filter(Boolean);
      status(fmt(n) + " moves \u00b7 ready in " + fmt((performance.now() - t0) / 1000, 2) + " s \u00b7 " +
        (VIEWS_[0].gl ? "WebGL" : "2-D canvas (no WebGL)") + (notes.length ? " \u00b7 " + notes[0] : ""));
      document.body.dataset.ready = "1";
      window.ncperf.readyAt = performance.now(); // ms since the navigation started
      window.ncperf.ready = true;
    });
  }

  // For tests and scripts: where a move is on screen, the current state.
  window.ncperf = {
    ready: false,
    state: state,
    camera: cam,
    programs: PROGRAMS,
    views: VIEWS_,
    screenOf: function (pi, move) {
      var v = VIEWS_[pi], p = v.prog, a = p.first[move], b = p.last[move], P = p.P, R = rotation();
      var q0 = v.project(R, P[3 * a], P[3 * a + 1], P[3 * a + 2]), q1 = v.project(R, P[3 * b], P[3 * b + 1], P[3 * b + 2]);
      var r = v.canvas.getBoundingClientRect();
      return [r.left + (q0[0] + q1[0]) / 2, r.top + (q0[1] + q1[1]) / 2];
    }
  };
  start().catch(function (e) {
    window.ncperfErrors.push(String(e && e.message || e));
    status("cannot show this file: " + (e && e.message || e), true);
    throw e;
  });
})();
