/* The motion viewer of motiondiff.export.html_viewer: a 2D canvas, a perspective camera and no library, so one
 * small HTML file works offline and alone. It reads the JSON in its sibling <script class="motion-data">
 * (html_viewer._payload) and draws, per frame: the ground grid and the root's trail on the floor, then far to near
 * either the mannequin body's pieces (capsules placed on the frame's joints) or the bones and the head; a button
 * switches. Drag turns the camera, the wheel zooms; '#frame=K' in the URL shows frame K. The container gets
 * data-frames (count), data-frame (shown) and data-view ('body' or 'bones') for tests and pages that embed it. */
(function () {
  'use strict';
  const root = document.currentScript.parentElement;
  const data = JSON.parse(root.querySelector('script.motion-data').textContent);

  // ---- the motion: frames x joints x 3 little-endian uint16 steps of data.step metres from data.origin ----
  const bytes = Uint8Array.from(atob(data.positions), (c) => c.charCodeAt(0));
  const steps = new Uint16Array(bytes.buffer);
  const FRAMES = data.frames, JOINTS = data.joints, LAST = FRAMES - 1;
  function point(frame, joint) { // metres, y up
    const i = (frame * JOINTS + joint) * 3;
    return data.origin.map((o, axis) => o + data.step * steps[i + axis]);
  }

  // ---- the page: title, canvas, controls ----
  function add(tag, cls, parent) {
    const e = document.createElement(tag);
    e.className = cls;
    parent.appendChild(e);
    return e;
  }
  const title = add('div', 'mv-title', root);
  const canvas = add('canvas', 'mv-canvas', add('div', 'mv-stage', root)); // sized by the stage, not its pixels
  const bar = add('div', 'mv-bar', root);
  const play = add('button', 'mv-play', bar);
  const slider = add('input', 'mv-slider', bar);
  const label = add('span', 'mv-label', bar);
  const toggle = data.body ? add('button', 'mv-view', bar) : null; // body <-> bones
  slider.type = 'range'; slider.min = 0; slider.max = LAST; slider.step = 1; slider.value = 0;
  const ctx = canvas.getContext('2d');

  // ---- the camera: orbits the centre of the motion's fixed box, which fits the canvas (times the user's zoom) ----
  const [[x0, x1], [y0, y1], [z0, z1]] = data.ranges;
  const centre = [(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2];
  const corners = [];
  for (const x of [x0, x1]) for (const y of [y0, y1]) for (const z of [z0, z1]) corners.push([x, y, z]);
  const radius = Math.hypot(x1 - x0, y1 - y0, z1 - z0) / 2;
  const camera = { azimuth: data.camera.azimuth, elevation: data.camera.elevation, zoom: 1 };
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const unit = (a) => { const n = Math.hypot(...a); return a.map((v) => v / n); };

  // project(p) -> {x, y} on the canvas, its depth, and how many pixels a metre spans there
  function makeProjection(width, height) {
    const ce = Math.cos(camera.elevation);
    const back = [ce * Math.cos(camera.azimuth), Math.sin(camera.elevation), ce * Math.sin(camera.azimuth)];
    const eye = centre.map((c, i) => c + 3 * radius * back[i]);
    const forward = back.map((v) => -v);
    const right = unit(cross(forward, [0, 1, 0]));
    const up = cross(right, forward);
    const toCamera = (p) => { const v = sub(p, eye); return [dot(v, right), dot(v, up), dot(v, forward)]; };
    let [lx, hx, ly, hy] = [Infinity, -Infinity, Infinity, -Infinity];
    for (const [x, y, z] of corners.map(toCamera)) {
      lx = Math.min(lx, x / z); hx = Math.max(hx, x / z);
      ly = Math.min(ly, y / z); hy = Math.max(hy, y / z);
    }
    const scale = 0.94 * camera.zoom * Math.min(width / (hx - lx), height / (hy - ly));
    const ox = width / 2 - scale * (lx + hx) / 2, oy = height / 2 + scale * (ly + hy) / 2;
    return (p) => {
      const [x, y, z] = toCamera(p);
      return { x: ox + scale * x / z, y: oy - scale * y / z, depth: z, perMetre: scale / z };
    };
  }

  // ---- what is drawn ----
  function line(a, b, color, width) {
    ctx.strokeStyle = color; ctx.lineWidth = width; ctx.lineCap = 'round';
    ctx.beginPath(); ctx.moveTo(a.x, a.y); ctx.lineTo(b.x, b.y); ctx.stroke();
  }
  function disc(p, color, r) {
    ctx.fillStyle = color;
    ctx.beginPath(); ctx.arc(p.x, p.y, r, 0, 2 * Math.PI); ctx.fill();
  }
  const style = data.style;
  const onFloor = (p) => [p[0], 0, p[2]];

  function drawFloor(frame, project) {
    const step = style.grid_step;
    for (let x = Math.ceil(x0 / step) * step; x <= x1; x += step) {
      line(project([x, 0, z0]), project([x, 0, z1]), style.grid, 1);
    }
    for (let z = Math.ceil(z0 / step) * step; z <= z1; z += step) {
      line(project([x0, 0, z]), project([x1, 0, z]), style.grid, 1);
    }
    if (!data.trail) return;
    ctx.strokeStyle = style.trail; ctx.lineWidth = 2.5; ctx.lineJoin = 'round';
    ctx.beginPath();
    for (let f = 0; f < FRAMES; f++) {
      const p = project(onFloor(point(f, 0)));
      if (f) ctx.lineTo(p.x, p.y); else ctx.moveTo(p.x, p.y);
    }
    ctx.stroke();
    const r = project(onFloor(point(frame, 0)));
    disc(r, style.trail, Math.max(3, style.root_radius * r.perMetre));
  }

  // A layer turns a frame into items {depth, draw()}, drawn far to near together with the other layers' items.
  function bones(frame, project) {
    const items = [];
    for (const chain of data.chains) {
      for (let k = 1; k < chain.joints.length; k++) {
        const a = project(point(frame, chain.joints[k - 1])), b = project(point(frame, chain.joints[k]));
        const width = Math.max(2, style.bone_width * (a.perMetre + b.perMetre) / 2);
        items.push({ depth: (a.depth + b.depth) / 2, draw: () => line(a, b, chain.color, width) });
      }
    }
    return items;
  }
  function head(frame, project) {
    if (data.head === null) return [];
    const h = project(point(frame, data.head));
    return [{ depth: h.depth, draw: () => disc(h, style.head, Math.max(4, style.head_radius * h.perMetre)) }];
  }

  // The body: each mannequin piece [joint, toward, reach, radius] x 2 ends + tint (html_viewer._body_pieces), its end
  // points placed as Mannequin.at places them, drawn as the outline of a capsule seen from the camera: two discs
  // (each end's radius, in perspective) and the lines touching both, shaded across as a lit tube.
  function endPoint(frame, joint, toward, reach) { // joint + reach * unit(joint - toward)
    const at = point(frame, joint);
    if (toward < 0 || reach === 0) return at;
    const bone = sub(at, point(frame, toward)), n = Math.hypot(...bone);
    return n > 1e-9 ? at.map((v, i) => v + reach * bone[i] / n) : at;
  }
  function rgb(hex, k) { // the colour times k (k > 1 goes towards white)
    const c = [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16));
    return `rgb(${c.map((v) => Math.round(k <= 1 ? v * k : v + (255 - v) * (k - 1))).join(',')})`;
  }
  function capsule(a, ra, b, rb, hex) {
    const dx = b.x - a.x, dy = b.y - a.y, d = Math.hypot(dx, dy);
    let fill;
    ctx.beginPath();
    if (d <= Math.abs(ra - rb) + 1e-3) { // one end's disc holds the other (a ball, or a piece seen end-on)
      const [c, r] = ra >= rb ? [a, ra] : [b, rb];
      ctx.arc(c.x, c.y, r, 0, 2 * Math.PI);
      fill = ctx.createRadialGradient(c.x - 0.35 * r, c.y - 0.4 * r, 0.1 * r, c.x, c.y, r);
    } else {
      const angle = Math.atan2(dy, dx), spread = Math.acos((ra - rb) / d);
      ctx.arc(a.x, a.y, ra, angle + spread, angle + 2 * Math.PI - spread);
      ctx.arc(b.x, b.y, rb, angle - spread, angle + spread);
      ctx.closePath();
      let [nx, ny] = [-dy / d, dx / d]; // across the piece, towards the light (upper left)
      if (nx + ny > 0) [nx, ny] = [-nx, -ny];
      const r = Math.max(ra, rb), mx = (a.x + b.x) / 2, my = (a.y + b.y) / 2;
      fill = ctx.createLinearGradient(mx + nx * r, my + ny * r, mx - nx * r, my - ny * r);
    }
    fill.addColorStop(0, rgb(hex, 1.15)); fill.addColorStop(0.35, rgb(hex, 1.0)); fill.addColorStop(1, rgb(hex, 0.6));
    ctx.fillStyle = fill; ctx.fill();
    ctx.strokeStyle = rgb(hex, 0.55); ctx.lineWidth = 1; ctx.stroke();
  }
  function body(frame, project) {
    return data.body.map(([ja, ta, ea, ra, jb, tb, eb, rb, tint]) => {
      const a = project(endPoint(frame, ja, ta, ea)), b = project(endPoint(frame, jb, tb, eb));
      const [pa, pb] = [Math.max(1.5, ra * a.perMetre), Math.max(1.5, rb * b.perMetre)]; // pixels
      return { depth: (a.depth + b.depth) / 2, draw: () => capsule(a, pa, b, pb, style.body[tint]) };
    });
  }
  let showBody = Boolean(data.body);
  const layers = () => (showBody ? [body] : [bones, head]);

  // ---- state and drawing ----
  let shown = 0, playing = false, run = 0;

  function titleAt(frame) { // the last segment that has started, as render.title_at
    let text = '';
    for (const [start, t] of data.titles) if (frame >= start) text = t;
    return text;
  }

  function draw() {
    const dpr = window.devicePixelRatio || 1;
    const width = canvas.clientWidth, height = canvas.clientHeight;
    if (canvas.width !== Math.round(width * dpr) || canvas.height !== Math.round(height * dpr)) {
      canvas.width = Math.round(width * dpr); canvas.height = Math.round(height * dpr);
    }
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.fillStyle = 'white'; ctx.fillRect(0, 0, width, height);
    const project = makeProjection(width, height);
    drawFloor(shown, project);
    const items = layers().flatMap((layer) => layer(shown, project));
    items.sort((a, b) => b.depth - a.depth).forEach((item) => item.draw());
    const text = titleAt(shown);
    title.textContent = text; title.style.display = text ? '' : 'none';
    slider.value = shown;
    label.textContent = `frame ${shown} / ${LAST}  (${(shown / data.fps).toFixed(2)} s)`;
    play.textContent = playing ? 'Pause' : 'Play';
    if (toggle) toggle.textContent = showBody ? 'Show bones' : 'Show body';
    root.dataset.frames = FRAMES; root.dataset.frame = shown; root.dataset.view = showBody ? 'body' : 'bones';
  }

  function show(frame) { shown = Math.max(0, Math.min(LAST, frame)); draw(); }
  function setPlaying(on) { // plays from the frame shown at the motion's fps, looping
    playing = on; draw();
    if (!on) return;
    const mine = ++run, started = performance.now(), from = shown;
    const tick = (now) => {
      if (!playing || run !== mine) return;
      show((from + Math.floor((now - started) * data.fps / 1000)) % FRAMES);
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  }

  play.addEventListener('click', () => setPlaying(!playing));
  if (toggle) toggle.addEventListener('click', () => { showBody = !showBody; draw(); });
  slider.addEventListener('input', () => { playing = false; show(parseInt(slider.value, 10)); });
  let drag = null;
  canvas.addEventListener('pointerdown', (e) => {
    drag = [e.clientX, e.clientY];
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener('pointerup', () => { drag = null; });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    camera.azimuth += 0.01 * (e.clientX - drag[0]);
    camera.elevation = Math.max(-0.2, Math.min(1.45, camera.elevation + 0.01 * (e.clientY - drag[1])));
    drag = [e.clientX, e.clientY];
    draw();
  });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    camera.zoom = Math.max(0.3, Math.min(10, camera.zoom * Math.exp(-0.001 * e.deltaY)));
    draw();
  }, { passive: false });

  function frameFromHash() { const m = /frame=(\d+)/.exec(window.location.hash); return m ? parseInt(m[1], 10) : null; }
  window.addEventListener('hashchange', () => {
    const k = frameFromHash();
    if (k !== null) { playing = false; show(k); }
  });
  new ResizeObserver(draw).observe(canvas);
  show(frameFromHash() ?? 0);
})();
