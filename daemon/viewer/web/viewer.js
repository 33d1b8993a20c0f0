// cblox viewer page: draws what cblox-viewer streams over /ws (daemon/viewer/viewer_model.h
// documents the messages): the mesh blocks of every subvolume in its own frame, placed by the
// subvolume's pose, with the trajectory, keyframes, subvolume bounds, the distance slice,
// events and every process's health. window.cbloxViewer is its state, for tests and the
// browser console.
'use strict';

(function () {
  const MODE_SURFACE = 0, MODE_SUBVOLUME = 1, MODE_HEIGHT = 2, MODE_NORMAL = 3;
  const UP_VECTORS = {
    'x': [1, 0, 0], 'y': [0, 1, 0], 'z': [0, 0, 1],
    '-x': [-1, 0, 0], '-y': [0, -1, 0], '-z': [0, 0, -1],
  };

  const view = {
    connected: false,
    connections: 0,       // sockets opened since the page loaded
    messages: 0,
    bytes: 0,
    mapEpoch: 0,
    complete: false,
    synced: false,
    blockSize: 0,
    upAxis: 'z',
    subvolumes: {},       // id -> {pose, active, blocks (in the page), expected (the viewer's)}
    blockCount: 0,
    trajectoryPoints: 0,
    keyframeCount: 0,
    events: [],
    processes: {},
    allowExport: false,
    colorMode: MODE_SURFACE,
    follow: false,
  };
  window.cbloxViewer = view;

  // ---- Scene.
  const container = document.getElementById('view');
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0x1e2228);
  container.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(60, 1, 0.05, 2000);
  camera.up.set(0, 0, 1);
  camera.position.set(6, -6, 5);
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;

  const vertexShader = [
    'precision highp float;',
    'uniform mat4 modelMatrix, modelViewMatrix, projectionMatrix;',
    'uniform mat3 normalMatrix;',
    'uniform vec3 up;',
    'attribute vec3 position, normal, color;',
    'varying vec3 vColor, vNormalView, vNormalWorld;',
    'varying float vHeight;',
    'void main() {',
    '  vec4 world = modelMatrix * vec4(position, 1.0);',
    '  vHeight = dot(world.xyz, up);',
    '  vColor = color;',
    '  vNormalView = normalMatrix * normal;',
    '  vNormalWorld = mat3(modelMatrix) * normal;',
    '  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);',
    '}'].join('\n');
  const fragmentShader = [
    'precision highp float;',
    'uniform int mode;',
    'uniform vec3 subColor;',
    'uniform float hMin, hMax;',
    'varying vec3 vColor, vNormalView, vNormalWorld;',
    'varying float vHeight;',
    'vec3 ramp(float t) {',
    '  t = clamp(t, 0.0, 1.0);',
    '  return clamp(vec3(1.5 - abs(4.0 * t - 3.0), 1.5 - abs(4.0 * t - 2.0),',
    '                    1.5 - abs(4.0 * t - 1.0)), 0.0, 1.0);',
    '}',
    'void main() {',
    '  vec3 base = vColor;',
    '  if (mode == 1) base = subColor;',
    '  if (mode == 2) base = ramp((vHeight - hMin) / max(hMax - hMin, 1e-3));',
    '  if (mode == 3) { gl_FragColor = vec4(0.5 + 0.5 * normalize(vNormalWorld), 1.0); return; }',
    '  float shade = 0.35 + 0.65 * abs(normalize(vNormalView).z);',
    '  gl_FragColor = vec4(base * shade, 1.0);',
    '}'].join('\n');

  const heightRange = { min: 0, max: 3 };
  function subvolumeColor(id) {
    const c = new THREE.Color();
    c.setHSL((id * 0.61803398875) % 1, 0.65, 0.55);
    return c;
  }
  function upVector() {
    const u = UP_VECTORS[view.upAxis] || UP_VECTORS.z;
    return new THREE.Vector3(u[0], u[1], u[2]);
  }

  const subvolumes = new Map();  // id -> {group, material, blocks: Map(key -> mesh), bounds}
  const mapRoot = new THREE.Group();
  scene.add(mapRoot);

  function subvolume(id) {
    let s = subvolumes.get(id);
    if (s) return s;
    const group = new THREE.Group();
    group.matrixAutoUpdate = false;
    group.visible = false;  // until its pose is known
    const material = new THREE.RawShaderMaterial({
      uniforms: {
        mode: { value: view.colorMode },
        subColor: { value: subvolumeColor(id) },
        up: { value: upVector() },
        hMin: { value: heightRange.min },
        hMax: { value: heightRange.max },
      },
      vertexShader, fragmentShader, side: THREE.DoubleSide,
    });
    const bounds = new THREE.LineSegments(
      new THREE.EdgesGeometry(new THREE.BoxBufferGeometry(1, 1, 1)),
      new THREE.LineBasicMaterial({ color: subvolumeColor(id) }));
    bounds.visible = false;
    group.add(bounds);
    mapRoot.add(group);
    s = { id, group, material, blocks: new Map(), bounds };
    subvolumes.set(id, s);
    view.subvolumes[id] = view.subvolumes[id] || { blocks: 0, expected: 0, pose: null, active: false };
    return s;
  }

  function dropSubvolume(id) {
    const s = subvolumes.get(id);
    if (!s) return;
    for (const mesh of s.blocks.values()) mesh.geometry.dispose();
    view.blockCount -= s.blocks.size;
    mapRoot.remove(s.group);
    s.material.dispose();
    subvolumes.delete(id);
    delete view.subvolumes[id];
  }

  function dropAllBlocks() {
    for (const s of subvolumes.values()) {
      for (const mesh of s.blocks.values()) {
        s.group.remove(mesh);
        mesh.geometry.dispose();
      }
      s.blocks.clear();
      view.subvolumes[s.id].blocks = 0;
    }
    view.blockCount = 0;
  }

  // ---- Mesh messages (binary).
  function onMeshMessage(buffer) {
    const dv = new DataView(buffer);
    let o = 0;
    const type = dv.getUint32(o, true); o += 4;
    if (type !== 1) return;
    const flags = dv.getUint32(o, true); o += 4;
    const blockSize = dv.getFloat32(o, true); o += 4;
    const numRemoved = dv.getUint32(o, true); o += 4;
    const numBlocks = dv.getUint32(o, true); o += 4;
    if (flags & 1) dropAllBlocks();
    for (let i = 0; i < numRemoved; ++i) { dropSubvolume(dv.getFloat64(o, true)); o += 8; }
    const quantum = blockSize / 32768;
    const pad4 = (n) => (n + 3) & ~3;
    for (let b = 0; b < numBlocks; ++b) {
      const id = dv.getFloat64(o, true); o += 8;
      const ix = dv.getInt32(o, true), iy = dv.getInt32(o + 4, true), iz = dv.getInt32(o + 8, true);
      o += 12;
      const nv = dv.getUint32(o, true), nt = dv.getUint32(o + 4, true);
      const hasColor = dv.getUint32(o + 8, true) !== 0;
      o += 12;
      const s = subvolume(id);
      const key = ix + ',' + iy + ',' + iz;
      const old = s.blocks.get(key);
      if (old) {
        s.group.remove(old);
        old.geometry.dispose();
        s.blocks.delete(key);
        view.blockCount -= 1;
        view.subvolumes[id].blocks -= 1;
      }
      if (nv === 0) continue;
      const q = new Int16Array(buffer, o, 3 * nv); o += pad4(6 * nv);
      const cx = (ix + 0.5) * blockSize, cy = (iy + 0.5) * blockSize, cz = (iz + 0.5) * blockSize;
      const positions = new Float32Array(3 * nv);
      for (let v = 0; v < nv; ++v) {
        positions[3 * v] = cx + q[3 * v] * quantum;
        positions[3 * v + 1] = cy + q[3 * v + 1] * quantum;
        positions[3 * v + 2] = cz + q[3 * v + 2] * quantum;
      }
      const colors = new Float32Array(3 * nv);
      if (hasColor) {
        const c = new Uint8Array(buffer, o, 3 * nv); o += pad4(3 * nv);
        for (let k = 0; k < 3 * nv; ++k) colors[k] = c[k] / 255;
      } else {
        colors.fill(0.7);
      }
      const index = new Uint16Array(buffer, o, 3 * nt); o += pad4(6 * nt);
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
      geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
      geometry.setIndex(new THREE.BufferAttribute(new Uint16Array(index), 1));
      geometry.computeVertexNormals();
      geometry.computeBoundingSphere();
      const mesh = new THREE.Mesh(geometry, s.material);
      mesh.userData.isBlock = true;
      s.group.add(mesh);
      s.blocks.set(key, mesh);
      view.blockCount += 1;
      view.subvolumes[id].blocks += 1;
    }
    updateSummary();
  }

  // ---- JSON messages.
  function onState(m) {
    if (m.map_epoch !== view.mapEpoch) view.mapEpoch = m.map_epoch;
    view.complete = m.complete;
    view.synced = m.synced;
    view.blockSize = m.block_size;
    view.allowExport = m.allow_export;
    document.getElementById('export').hidden = !m.allow_export;
    if (m.up_axis !== view.upAxis) {
      view.upAxis = m.up_axis;
      const u = upVector();
      camera.up.copy(u);
      for (const s of subvolumes.values()) s.material.uniforms.up.value = u;
      fitView();
    }
    const seen = new Set();
    let lo = Infinity, hi = -Infinity;
    const up = upVector();
    for (const sv of m.subvolumes) {
      seen.add(sv.id);
      const s = subvolume(sv.id);
      s.group.matrix.fromArray(sv.pose);
      s.group.matrixWorldNeedsUpdate = true;
      s.group.visible = true;
      const min = new THREE.Vector3().fromArray(sv.min), max = new THREE.Vector3().fromArray(sv.max);
      const size = new THREE.Vector3().subVectors(max, min);
      s.bounds.visible = document.getElementById('show-bounds').checked && size.lengthSq() > 0;
      if (size.lengthSq() > 0) {
        s.bounds.position.addVectors(min, max).multiplyScalar(0.5);
        s.bounds.scale.set(Math.max(size.x, 1e-3), Math.max(size.y, 1e-3), Math.max(size.z, 1e-3));
        // Height range of the map, from the corners of the bounds in G.
        for (let c = 0; c < 8; ++c) {
          const p = new THREE.Vector3(c & 1 ? max.x : min.x, c & 2 ? max.y : min.y, c & 4 ? max.z : min.z);
          p.applyMatrix4(s.group.matrix);
          const h = p.dot(up);
          lo = Math.min(lo, h); hi = Math.max(hi, h);
        }
      }
      s.bounds.material.linewidth = sv.active ? 2 : 1;
      const entry = view.subvolumes[sv.id];
      entry.pose = sv.pose.slice();
      entry.active = sv.active;
      entry.expected = sv.mesh_blocks;
    }
    if (m.subvolumes_epoch_matches) {
      for (const id of Array.from(subvolumes.keys())) if (!seen.has(id)) dropSubvolume(id);
    }
    if (isFinite(lo) && isFinite(hi)) {
      heightRange.min = lo; heightRange.max = hi;
      for (const s of subvolumes.values()) {
        s.material.uniforms.hMin.value = lo;
        s.material.uniforms.hMax.value = hi;
      }
    }
    if (!view.fitted && view.blockCount > 0) fitView();
    updateSummary();
  }

  // Trajectory: a line in a growing buffer.
  let trajectoryPositions = new Float32Array(3 * 4096);
  const trajectoryGeometry = new THREE.BufferGeometry();
  trajectoryGeometry.setAttribute('position', new THREE.BufferAttribute(trajectoryPositions, 3));
  trajectoryGeometry.setDrawRange(0, 0);
  const trajectory = new THREE.Line(trajectoryGeometry, new THREE.LineBasicMaterial({ color: 0xffd24a }));
  trajectory.frustumCulled = false;
  scene.add(trajectory);
  function onTrajectory(m) {
    const start = m.reset ? 0 : view.trajectoryPoints;
    const total = start + m.points.length / 3;
    if (3 * total > trajectoryPositions.length) {
      let capacity = trajectoryPositions.length;
      while (capacity < 3 * total) capacity *= 2;
      const grown = new Float32Array(capacity);
      grown.set(trajectoryPositions.subarray(0, 3 * start));
      trajectoryPositions = grown;
      trajectoryGeometry.setAttribute('position', new THREE.BufferAttribute(trajectoryPositions, 3));
    }
    trajectoryPositions.set(m.points, 3 * start);
    trajectoryGeometry.attributes.position.needsUpdate = true;
    trajectoryGeometry.setDrawRange(0, total);
    view.trajectoryPoints = total;
  }

  const keyframeGeometry = new THREE.BufferGeometry();
  keyframeGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(0), 3));
  const keyframes = new THREE.Points(keyframeGeometry,
    new THREE.PointsMaterial({ color: 0xff6b6b, size: 6, sizeAttenuation: false }));
  keyframes.frustumCulled = false;
  scene.add(keyframes);
  function onKeyframes(m) {
    keyframeGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(m.points), 3));
    view.keyframeCount = m.points.length / 3;
  }

  const vehicle = new THREE.AxesHelper(0.4);
  vehicle.matrixAutoUpdate = false;
  vehicle.visible = false;
  scene.add(vehicle);
  const vehiclePosition = new THREE.Vector3();
  function onVehicle(m) {
    const previous = vehiclePosition.clone();
    vehicle.matrix.fromArray(m.pose);
    vehicle.matrixWorldNeedsUpdate = true;
    vehicle.visible = true;
    vehiclePosition.setFromMatrixPosition(vehicle.matrix);
    if (view.follow) {
      const delta = vehiclePosition.clone().sub(previous);
      camera.position.add(delta);
      controls.target.add(delta);
    }
  }

  // The distance slice: a plane textured by distance (blue far, red near, dark unknown).
  let slice = null;
  function onSlice(m) {
    const data = new Uint8Array(4 * m.nu * m.nv);
    for (let k = 0; k < m.nu * m.nv; ++k) {
      const d = m.distance_mm[k];
      if (d === null) { data[4 * k + 3] = 0; continue; }
      const t = Math.max(0, Math.min(1, d / 1000 / Math.max(m.max_distance_m, 1e-3)));
      data[4 * k] = Math.round(255 * (1 - t));
      data[4 * k + 1] = Math.round(255 * Math.min(1, 2 * t) * (1 - t) * 1.6);
      data[4 * k + 2] = Math.round(255 * t);
      data[4 * k + 3] = d <= 0 ? 255 : 170;
    }
    const texture = new THREE.DataTexture(data, m.nu, m.nv, THREE.RGBAFormat);
    texture.magFilter = THREE.NearestFilter;
    texture.needsUpdate = true;
    if (slice) { scene.remove(slice); slice.geometry.dispose(); slice.material.map.dispose(); slice.material.dispose(); }
    const w = m.nu * m.resolution, h = m.nv * m.resolution;
    slice = new THREE.Mesh(new THREE.PlaneBufferGeometry(w, h),
      new THREE.MeshBasicMaterial({ map: texture, transparent: true, side: THREE.DoubleSide, depthWrite: false }));
    // The plane spans local x, y: map them onto G's axes u, v; its normal onto the up axis.
    const axes = [new THREE.Vector3(1, 0, 0), new THREE.Vector3(0, 1, 0), new THREE.Vector3(0, 0, 1)];
    const u = axes[m.axes[0]], v = axes[m.axes[1]], n = new THREE.Vector3().crossVectors(u, v);
    const center = new THREE.Vector3();
    center.addScaledVector(u, m.origin[0] + w / 2).addScaledVector(v, m.origin[1] + h / 2);
    center.addScaledVector(n, m.level);
    slice.matrixAutoUpdate = false;
    slice.matrix.makeBasis(u, v, n).setPosition(center);
    slice.visible = document.getElementById('show-slice').checked;
    slice.userData.isSlice = true;
    scene.add(slice);
    view.slice = { nu: m.nu, nv: m.nv, level: m.level };
  }

  // ---- Events and health.
  function onEvents(m) {
    const list = document.getElementById('events');
    for (const e of m.events) {
      view.events.push(e);
      const li = document.createElement('li');
      li.className = 'kind-' + e.kind;
      const when = e.utime ? new Date(e.utime / 1000).toLocaleTimeString() : '';
      li.textContent = (when ? when + '  ' : '') + e.kind + ': ' + e.text;
      list.insertBefore(li, list.firstChild);
    }
    while (list.children.length > 200) list.removeChild(list.lastChild);
    drawTimeline();
  }
  function drawTimeline() {
    const strip = document.getElementById('timeline-strip');
    strip.innerHTML = '';
    const timed = view.events.filter((e) => e.utime > 0);
    if (timed.length === 0) return;
    const t0 = timed[0].utime, t1 = Math.max(timed[timed.length - 1].utime, t0 + 1);
    const colors = { loop: '#f5c26b', fusion: '#8ab8f0' };
    for (const e of timed) {
      const mark = document.createElement('div');
      mark.className = 'mark';
      mark.style.left = (100 * (e.utime - t0) / (t1 - t0)).toFixed(2) + '%';
      mark.style.background = colors[e.kind] || '#c0a0f0';
      mark.title = e.kind + ': ' + e.text;
      strip.appendChild(mark);
    }
  }

  function counter(p, names) {
    for (const n of names) if (p.counters[n] !== undefined) return [n, p.counters[n]];
    return null;
  }
  function onHealth(m) {
    const now = Date.now() * 1000;
    for (const p of m.processes) {
      const prev = view.processes[p.name];
      if (prev && prev.pid === p.pid && p.utime > prev.utime) {
        p.first = prev.first && prev.first.pid === p.pid ? prev.first : prev;
      } else if (prev && prev.pid === p.pid) {
        p.first = prev.first;
      }
      view.processes[p.name] = p;
    }
    const rows = document.getElementById('health-rows');
    rows.innerHTML = '';
    for (const name of Object.keys(view.processes).sort()) {
      const p = view.processes[name];
      const f = p.first;
      const dt = f ? (p.utime - f.utime) / 1e6 : 0;
      const state = p.state.length > 40 ? p.state.slice(0, 39) + '\u2026' : p.state;
      const cells = [name.replace(/^cblox-/, ''), state, ((now - p.utime) / 1e6).toFixed(1) + ' s'];
      const frames = counter(p, ['frames_published', 'frames_processed', 'frames_integrated', 'frames_received']);
      cells.push(frames && f && dt > 0 && f.counters[frames[0]] !== undefined
        ? ((frames[1] - f.counters[frames[0]]) / dt).toFixed(1) : '-');
      const dropped = counter(p, ['frames_dropped', 'source_gaps']);
      cells.push(dropped ? String(dropped[1]) : '-');
      cells.push(f && dt > 0 && p.counters.cpu_ms !== undefined
        ? (100 * (p.counters.cpu_ms - f.counters.cpu_ms) / (dt * 1000)).toFixed(0) + ' %' : '-');
      cells.push(p.counters.rss_kib !== undefined ? (p.counters.rss_kib / 1024).toFixed(0) + ' MiB' : '-');
      const tr = document.createElement('tr');
      for (const c of cells) { const td = document.createElement('td'); td.textContent = c; tr.appendChild(td); }
      rows.appendChild(tr);
    }
  }

  function onExport(m) {
    const status = document.getElementById('export-status');
    status.textContent = m.ok ? '' : m.message;
    view.lastExport = m;
    if (m.ok && m.url) {
      const a = document.createElement('a');
      a.href = m.url;
      a.download = 'cblox_mesh.ply';
      a.textContent = 'download the PLY';
      status.appendChild(a);
    }
  }

  // ---- The socket, reconnecting.
  let socket = null;
  function connect() {
    const url = (location.protocol === 'https:' ? 'wss://' : 'ws://') + location.host + '/ws';
    socket = new WebSocket(url);
    socket.binaryType = 'arraybuffer';
    socket.onopen = () => {
      view.connected = true;
      view.connections += 1;
      setConnection();
    };
    socket.onclose = () => {
      view.connected = false;
      setConnection();
      setTimeout(connect, 1000);
    };
    socket.onmessage = (e) => {
      view.messages += 1;
      draw();
      if (typeof e.data === 'string') {
        view.bytes += e.data.length;
        const m = JSON.parse(e.data);
        if (m.type === 'state') onState(m);
        else if (m.type === 'trajectory') onTrajectory(m);
        else if (m.type === 'keyframes') onKeyframes(m);
        else if (m.type === 'vehicle') onVehicle(m);
        else if (m.type === 'events') onEvents(m);
        else if (m.type === 'health') onHealth(m);
        else if (m.type === 'slice') onSlice(m);
        else if (m.type === 'export') onExport(m);
      } else {
        view.bytes += e.data.byteLength;
        onMeshMessage(e.data);
      }
    };
  }
  function setConnection() {
    const c = document.getElementById('connection');
    c.textContent = view.connected ? 'connected' : 'disconnected, retrying';
    c.className = view.connected ? 'good' : 'bad';
  }
  function updateSummary() {
    const n = Object.keys(view.subvolumes).length;
    document.getElementById('summary').textContent =
      n + ' subvolumes, ' + view.blockCount + ' mesh blocks' +
      (view.complete ? '' : view.synced ? ' (more coming)' : ' (waiting for a refresh)');
  }

  // ---- Controls.
  document.getElementById('controls').addEventListener('change', draw);
  document.getElementById('controls').addEventListener('click', draw);
  document.getElementById('color-mode').addEventListener('change', (e) => {
    view.colorMode = Number(e.target.value);
    for (const s of subvolumes.values()) s.material.uniforms.mode.value = view.colorMode;
  });
  document.getElementById('show-bounds').addEventListener('change', (e) => {
    for (const s of subvolumes.values()) s.bounds.visible = e.target.checked;
  });
  document.getElementById('show-trajectory').addEventListener('change', (e) => { trajectory.visible = e.target.checked; });
  document.getElementById('show-keyframes').addEventListener('change', (e) => { keyframes.visible = e.target.checked; });
  document.getElementById('show-slice').addEventListener('change', (e) => { if (slice) slice.visible = e.target.checked; });
  document.getElementById('follow').addEventListener('change', (e) => { view.follow = e.target.checked; });
  document.getElementById('reset-view').addEventListener('click', fitView);
  document.getElementById('export').addEventListener('click', () => {
    if (socket && socket.readyState === WebSocket.OPEN) {
      socket.send(JSON.stringify({ type: 'export' }));
      document.getElementById('export-status').textContent = 'exporting...';
    }
  });

  // The world box of the mesh blocks (all subvolumes, or one).
  function meshBox(id) {
    const box = new THREE.Box3();
    mapRoot.updateMatrixWorld(true);
    for (const s of subvolumes.values()) {
      if (id !== undefined && s.id !== id) continue;
      if (!s.group.visible) continue;
      for (const mesh of s.blocks.values()) box.expandByObject(mesh);
    }
    return box;
  }
  view.worldBox = (id) => {
    const b = meshBox(id);
    return b.isEmpty() ? null : { min: b.min.toArray(), max: b.max.toArray() };
  };

  function fitView() {
    const box = meshBox();
    if (box.isEmpty()) return;
    view.fitted = true;
    const center = box.getCenter(new THREE.Vector3());
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 0.5);
    const up = upVector();
    // From above and to the side, so that the floor and the walls both show.
    const side = Math.abs(up.z) > 0.5 ? new THREE.Vector3(1, -1, 0) : new THREE.Vector3(1, 0, -1);
    side.normalize();
    camera.up.copy(up);
    camera.position.copy(center).addScaledVector(side, radius * 1.1).addScaledVector(up, radius * 1.2);
    camera.near = radius / 100;
    camera.far = radius * 20;
    camera.updateProjectionMatrix();
    controls.target.copy(center);
    controls.update();
  }
  view.fitView = fitView;

  // The share of the canvas the mesh covers: the scene drawn with only the mesh blocks,
  // pixels that differ from the background counted.
  view.coverage = () => {
    const hidden = [];
    scene.traverse((o) => {
      if (o.visible && !o.userData.isBlock && (o.isLine || o.isLineSegments || o.isPoints ||
          o.userData.isSlice || o === vehicle)) { hidden.push(o); o.visible = false; }
    });
    renderer.render(scene, camera);
    const gl = renderer.getContext();
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    const pixels = new Uint8Array(4 * w * h);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
    for (const o of hidden) o.visible = true;
    let covered = 0;
    for (let i = 0; i < w * h; ++i) {
      const r = pixels[4 * i], g = pixels[4 * i + 1], b = pixels[4 * i + 2];
      if (Math.abs(r - 0x1e) + Math.abs(g - 0x22) + Math.abs(b - 0x28) > 6) covered += 1;
    }
    return covered / (w * h);
  };

  function resize() {
    const w = container.clientWidth, h = container.clientHeight;
    renderer.setSize(w, h);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
  }
  window.addEventListener('resize', resize);
  resize();
  // Drawn when something changed (a message, the camera, the window), not every frame:
  // an idle page costs no CPU.
  let drawPending = false;
  function draw() {
    if (drawPending) return;
    drawPending = true;
    requestAnimationFrame(() => {
      drawPending = false;
      renderer.render(scene, camera);
    });
  }
  view.draw = draw;
  controls.addEventListener('change', draw);
  window.addEventListener('resize', draw);
  draw();
  connect();
})();
