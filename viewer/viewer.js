// The page of `ibl view` (docs/VIEWER.md). Reads the JSON block the CLI wrote (the probe's
// uniform block and textures, the sphere grid's materials, the manifest), uploads it for
// shaders/ibl.glsl exactly as docs/SHADERS.md binds it, and draws viewer/scene.frag with
// the text of ibl.glsl in front of it. No formula of the shading lives here: the script
// moves the camera, sets uniforms and reports. window.iblViewer is the page's small API
// (the browser tests drive it; it is also handy from the console).
'use strict';
(function () {
  const $ = (id) => document.getElementById(id);
  const api = { ready: false, error: null, frameMs: 0, drawMs: 0 };
  window.iblViewer = api;

  function fail(message) {
    api.error = message;
    const box = $('error');
    box.textContent = 'ibl view: ' + message;
    box.hidden = false;
    console.error('ibl view: ' + message);
  }

  // ---- the data block -------------------------------------------------------------------
  const PROBE_BYTES = 384, OFFSET_LEVELS = 352, OFFSET_SH_KIND = 356, OFFSET_HAS_MIRROR = 368;

  function fnv1a(bytes) {
    let h = 0x811c9dc5;
    for (let i = 0; i < bytes.length; i++) h = Math.imul(h ^ bytes[i], 16777619) >>> 0;
    return h >>> 0;
  }

  function decodeBase64(text, what) {
    let bin;
    try {
      bin = atob(text);
    } catch (e) {
      throw new Error(what + ' is corrupted (not base64: ' + e.message + ')');
    }
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out;
  }

  // Bytes a texture must have: texels of every level times channels times 2 (f16) or 4 (f32).
  function expectedBytes(t) {
    let texels = 0;
    for (let k = 0; k < t.levels; k++) {
      const w = Math.max(t.width >> k, 1), h = Math.max(t.height >> k, 1);
      texels += w * h * (t.target === 'cube' ? 6 : t.depth);
    }
    return texels * t.channels * (t.type === 'f32' ? 4 : 2);
  }

  function decodeTexture(name, t) {
    const what = 'embedded texture "' + name + '"';
    if (!t || typeof t.data !== 'string') throw new Error(what + ' is missing');
    const bytes = decodeBase64(t.data, what);
    if (bytes.length !== t.bytes || bytes.length !== expectedBytes(t))
      throw new Error(what + ' is corrupted: ' + bytes.length + ' bytes, expected ' + expectedBytes(t));
    const sum = fnv1a(bytes);
    if (sum !== t.fnv)
      throw new Error(what + ' is corrupted: checksum ' + sum.toString(16) + ', expected ' + t.fnv.toString(16));
    return bytes;
  }

  // ---- WebGL2 upload (docs/SHADERS.md "Textures and samplers") ----------------------------
  const UNITS = ['specular', 'mirror', 'irradiance', 'splitsum', 'ambient_brdf', 'tonemap'];
  const SAMPLERS = ['u_specular', 'u_mirror', 'u_irradiance', 'u_splitsum', 'u_ambient', 'u_tonemap'];

  function uploadTexture(gl, t, bytes) {
    const tex = gl.createTexture();
    const f32 = t.type === 'f32';
    const formats = [null, [gl.R16F, gl.RED], [gl.RG16F, gl.RG], null, [gl.RGBA16F, gl.RGBA]];
    const formats32 = [null, [gl.R32F, gl.RED], [gl.RG32F, gl.RG], null, [gl.RGBA32F, gl.RGBA]];
    const [internal, format] = (f32 ? formats32 : formats)[t.channels];
    const type = f32 ? gl.FLOAT : gl.HALF_FLOAT;
    const view = (offset, count) => f32 ? new Float32Array(bytes.buffer, offset, count)
                                        : new Uint16Array(bytes.buffer, offset, count);
    const size = f32 ? 4 : 2;
    const target = { cube: gl.TEXTURE_CUBE_MAP, '2d': gl.TEXTURE_2D, '3d': gl.TEXTURE_3D }[t.target];
    gl.bindTexture(target, tex);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    let offset = 0;
    for (let k = 0; k < t.levels; k++) {
      const w = Math.max(t.width >> k, 1), h = Math.max(t.height >> k, 1);
      const count = w * h * t.channels;
      if (t.target === 'cube') {
        for (let f = 0; f < 6; f++, offset += count * size) // +X -X +Y -Y +Z -Z, as ibl stores them
          gl.texImage2D(gl.TEXTURE_CUBE_MAP_POSITIVE_X + f, k, internal, w, h, 0, format, type, view(offset, count));
      } else if (t.target === '3d') {
        gl.texImage3D(target, k, internal, w, h, t.depth, 0, format, type, view(offset, count * t.depth));
        offset += count * t.depth * size;
      } else {
        gl.texImage2D(target, k, internal, w, h, 0, format, type, view(offset, count));
        offset += count * size;
      }
    }
    const filter = f32 ? gl.NEAREST : gl.LINEAR; // the display table is read with texelFetch
    gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, filter);
    gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, t.levels > 1 ? gl.LINEAR_MIPMAP_LINEAR : filter);
    gl.texParameteri(target, gl.TEXTURE_BASE_LEVEL, 0);
    gl.texParameteri(target, gl.TEXTURE_MAX_LEVEL, t.levels - 1);
    for (const wrap of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T, gl.TEXTURE_WRAP_R])
      gl.texParameteri(target, wrap, gl.CLAMP_TO_EDGE);
    return { tex, target };
  }

  const VERTEX = '#version 300 es\nvoid main() {\n' +
    '  vec2 p = vec2(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID & 2) * 2 - 1));\n' +
    '  gl_Position = vec4(p, 0.0, 1.0);\n}\n';

  function compile(gl, type, source, what) {
    const s = gl.createShader(type);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS))
      throw new Error(what + ' does not compile:\n' + gl.getShaderInfoLog(s));
    return s;
  }

  function makeProgram(gl, iblGlsl, sceneFrag) {
    const p = gl.createProgram();
    gl.attachShader(p, compile(gl, gl.VERTEX_SHADER, VERTEX, 'the vertex shader'));
    // "#version" first, then ibl.glsl verbatim, then the scene (docs/SHADERS.md "Dialects")
    gl.attachShader(p, compile(gl, gl.FRAGMENT_SHADER, '#version 300 es\n' + iblGlsl + '\n' + sceneFrag,
                               'ibl.glsl + scene.frag'));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error('link: ' + gl.getProgramInfoLog(p));
    return p;
  }

  // ---- the options of ibl.glsl, read from its own #defines --------------------------------
  function defines(glsl, prefix) {
    const out = [];
    const re = new RegExp('#define IBL_' + prefix + '_(\\w+) (\\d+)', 'g');
    let m;
    while ((m = re.exec(glsl))) out.push([Number(m[2]), m[1].toLowerCase().replace(/_/g, '-')]);
    return out;
  }

  // ---- state ------------------------------------------------------------------------------
  const state = {
    scene: 0, bg: 0, model: 0, base: '#e6c27a', metallic: 1, roughness: 0.3, f0: 0.5,
    shininess: 2.5, ball_ao: 1, sphere_ao: 0, split: false, split_at: 0.5, exposure: 0,
    tonemap: 0, continuous: false,
    A: { so: 0, mix: 0, energy: 0, irradiance: 0, horizon: 0, lookup: 0, levels: 0, bp_diffuse: 0 },
    B: { so: 0, mix: 0, energy: 0, irradiance: 0, horizon: 0, lookup: 0, levels: 0, bp_diffuse: 0 },
    camera: null,
  };

  function defaultCamera(scene) {
    return scene === 1 ? { yaw: 0.5, pitch: 0.25, dist: 9.5, target: [0, 0.1, 0] }
                       : { yaw: 0, pitch: 0, dist: 12, target: [0, 0, 0] };
  }

  const srgbToLinear = (c) => c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4);
  function hexToLinear(hex) {
    const v = parseInt(hex.slice(1), 16);
    return [v >> 16 & 255, v >> 8 & 255, v & 255].map((c) => srgbToLinear(c / 255));
  }

  // ---- camera: orbit about a target; the field of view frames the grid as render.c does ----
  function cameraVectors(cam, width, height) {
    const cp = Math.cos(cam.pitch), sp = Math.sin(cam.pitch);
    const dir = [Math.sin(cam.yaw) * cp, sp, Math.cos(cam.yaw) * cp];
    const eye = cam.target.map((t, i) => t + cam.dist * dir[i]);
    const forward = dir.map((c) => -c);
    const norm = (v) => { const l = Math.hypot(...v); return v.map((c) => c / l); };
    const right = norm([-forward[2], 0, forward[0]]); // forward x (0, 1, 0)
    const up = [right[1] * forward[2] - right[2] * forward[1], right[2] * forward[0] - right[0] * forward[2],
                right[0] * forward[1] - right[1] * forward[0]];
    // render.c: at least 2 units above and below and 4.3 to each side at distance 12
    const aspect = width / height;
    let half_h = 2.0;
    if (half_h * aspect < 4.3) half_h = 4.3 / aspect;
    const tanY = half_h / 12;
    return { eye, forward, right, up, tan: [tanY * aspect, tanY] };
  }

  // ---- the viewer ----------------------------------------------------------------------------
  let gl, program, uniforms = {}, ubo = {}, probeBytes, data, glsl, fixedSize = null;

  function init() {
    data = JSON.parse($('ibl-data').textContent);
    glsl = $('ibl-glsl').textContent;
    if (data.format !== 'ibl-viewer' || data.version !== 1) throw new Error('unknown data block');
    probeBytes = decodeBase64(data.probe, 'the probe block');
    if (probeBytes.length !== PROBE_BYTES) throw new Error('the probe block is corrupted');
    const textures = {};
    for (const name of UNITS) textures[name] = decodeTexture(name, data.textures[name]);
    gl = $('canvas').getContext('webgl2', { antialias: false, preserveDrawingBuffer: true, alpha: false });
    if (!gl) throw new Error('this browser has no WebGL2');
    program = makeProgram(gl, glsl, $('ibl-scene-frag').textContent);
    gl.useProgram(program);
    UNITS.forEach((name, unit) => {
      gl.activeTexture(gl.TEXTURE0 + unit); // each texture stays bound to its own unit
      uploadTexture(gl, data.textures[name], textures[name]);
      gl.uniform1i(gl.getUniformLocation(program, SAMPLERS[unit]), unit);
    });
    gl.activeTexture(gl.TEXTURE0);
    gl.uniformBlockBinding(program, gl.getUniformBlockIndex(program, 'ProbeBlock'), 0);
    for (const name of ['A', 'B']) ubo[name] = gl.createBuffer();
    const n = gl.getProgramParameter(program, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < n; i++) {
      const info = gl.getActiveUniform(program, i);
      const key = info.name.replace(/\[0\]$/, '');
      uniforms[key] = gl.getUniformLocation(program, info.name);
    }
    gl.bindVertexArray(gl.createVertexArray());
    const err = gl.getError();
    if (err !== gl.NO_ERROR) throw new Error('WebGL error 0x' + err.toString(16) + ' while uploading the bake');
    setSphereUniforms();
    // the exposure `ibl render` would pick; the slider spans 12 EV about it
    state.exposure = data.exposure;
    $('exposure').min = Math.floor(data.exposure) - 12;
    $('exposure').max = Math.ceil(data.exposure) + 12;
  }

  function setSphereUniforms() {
    const params = new Float32Array(84), base = new Float32Array(84), f0 = new Float32Array(84);
    data.spheres.slice(0, 21).forEach((s, i) => {
      params.set([s.model, s.metallic, s.roughness, s.shininess], 4 * i);
      base.set(s.base, 4 * i);
      f0.set(s.f0, 4 * i);
    });
    gl.uniform4fv(uniforms.u_params, params);
    gl.uniform4fv(uniforms.u_base, base);
    gl.uniform4fv(uniforms.u_f0, f0);
  }

  const probeView = () => new DataView(probeBytes.buffer);
  const levelCount = () => probeView().getInt32(OFFSET_LEVELS, true);
  const hasMirror = () => probeView().getInt32(OFFSET_HAS_MIRROR, true) !== 0;
  const defaultShKind = () => probeView().getInt32(OFFSET_SH_KIND, true);
  const hasIrradianceMap = () => data.textures.irradiance.width > 1;

  // The probe block of a variant: the bake's, with the irradiance source it asks for.
  function uploadProbe(name, variant) {
    const bytes = probeBytes.slice();
    new DataView(bytes.buffer).setInt32(OFFSET_SH_KIND, variant.irradiance, true);
    gl.bindBuffer(gl.UNIFORM_BUFFER, ubo[name]);
    gl.bufferData(gl.UNIFORM_BUFFER, bytes, gl.DYNAMIC_DRAW);
  }

  function resize() {
    const c = $('canvas');
    const dpr = window.devicePixelRatio || 1;
    const w = fixedSize ? fixedSize[0] : Math.max(1, Math.round(c.clientWidth * dpr));
    const h = fixedSize ? fixedSize[1] : Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) {
      c.width = w;
      c.height = h;
    }
    return [w, h];
  }

  function drawVariant(name, x0, x1, h) {
    const v = state[name];
    uploadProbe(name, v);
    gl.bindBufferBase(gl.UNIFORM_BUFFER, 0, ubo[name]);
    gl.uniform4i(uniforms.u_desc0, v.energy, v.so, v.mix, v.horizon);
    gl.uniform4i(uniforms.u_desc1, v.bp_diffuse, 0, v.levels, v.lookup);
    gl.scissor(x0, 0, x1 - x0, h);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  // mode: 0 the image, 1 linear radiance, 2 the object mask
  function draw(mode) {
    const [w, h] = resize();
    const t0 = performance.now();
    gl.viewport(0, 0, w, h);
    if (!state.camera) state.camera = defaultCamera(state.scene);
    const cam = cameraVectors(state.camera, w, h);
    gl.uniform2f(uniforms.u_size, w, h);
    gl.uniform3fv(uniforms.u_eye, cam.eye);
    gl.uniform3fv(uniforms.u_right, cam.right);
    gl.uniform3fv(uniforms.u_up, cam.up);
    gl.uniform3fv(uniforms.u_forward, cam.forward);
    gl.uniform2fv(uniforms.u_tan_half, cam.tan);
    gl.uniform1i(uniforms.u_scene, state.scene);
    gl.uniform1f(uniforms.u_bg_lod, state.bg);
    gl.uniform1f(uniforms.u_horizon_k, 0);
    gl.uniform1f(uniforms.u_sphere_ao_min, state.sphere_ao);
    gl.uniform1f(uniforms.u_ball_ao, state.ball_ao);
    gl.uniform4f(uniforms.u_mat_params, state.model, state.metallic, state.roughness,
                 Math.pow(10, state.shininess));
    gl.uniform3fv(uniforms.u_mat_base, hexToLinear(state.base));
    gl.uniform3f(uniforms.u_mat_f0, state.f0, state.f0, state.f0);
    gl.uniform1f(uniforms.u_exposure, state.exposure);
    gl.uniform1i(uniforms.u_tonemap_row, state.tonemap);
    gl.uniform1i(uniforms.u_linear, mode === 1 ? 1 : 0);
    gl.uniform1i(uniforms.u_mask, mode === 2 ? 1 : 0);
    gl.enable(gl.SCISSOR_TEST);
    const split = state.split ? Math.round(state.split_at * w) : w;
    if (split > 0) drawVariant('A', 0, split, h);
    if (split < w) drawVariant('B', split, w, h);
    gl.disable(gl.SCISSOR_TEST);
    updateSplitOverlay(w);
    return t0;
  }

  // Draws and waits for the GPU (a one-pixel read): the time of one frame's work.
  function drawSynced(mode) {
    const t0 = draw(mode || 0);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
    api.drawMs = performance.now() - t0;
    return api.drawMs;
  }

  // ---- frame loop and statistics ----------------------------------------------------------
  let pending = false, lastFrame = 0, frameEma = 0;
  function requestDraw() {
    if (pending || !api.ready) return;
    pending = true;
    requestAnimationFrame(frame);
  }
  function frame(now) {
    pending = false;
    drawSynced();
    if (state.continuous) {
      if (lastFrame) frameEma = frameEma ? 0.9 * frameEma + 0.1 * (now - lastFrame) : now - lastFrame;
      lastFrame = now;
      api.frameMs = frameEma;
      requestDraw();
    } else {
      lastFrame = 0;
    }
    showStats();
  }
  function showStats() {
    const c = $('canvas');
    let text = c.width + '\u00d7' + c.height + '  draw ' + api.drawMs.toFixed(1) + ' ms';
    if (state.continuous && api.frameMs)
      text += '  frame ' + api.frameMs.toFixed(1) + ' ms (' + (1000 / api.frameMs).toFixed(0) + ' fps)';
    $('stats').textContent = text;
  }

  function updateSplitOverlay(w) {
    const on = state.split;
    $('split-line').hidden = !on;
    $('split-labels').hidden = !on;
    if (!on) return;
    const pct = (100 * Math.round(state.split_at * w) / w) + '%';
    $('split-line').style.left = pct;
    $('label-a').style.right = 'calc(100% - ' + pct + ' + 8px)';
    $('label-b').style.left = 'calc(' + pct + ' + 8px)';
  }

  // ---- controls ------------------------------------------------------------------------------
  function variantRows() {
    const irr = [];
    if (hasIrradianceMap()) irr.push([0, 'irradiance map']);
    if (data.sh_bands > 0) irr.push([1, 'SH (9 coefficients)']);
    return [
      ['so', 'Spec. occl.', defines(glsl, 'SO')],
      ['mix', 'Composition', defines(glsl, 'MIX')],
      ['energy', 'Energy comp.', defines(glsl, 'ENERGY')],
      ['irradiance', 'Diffuse', irr],
      ['horizon', 'Horizon occl.', [[0, 'off'], [1, 'on']]],
      ['lookup', 'Lookup dir.', [[0, 'dominant'], [1, 'mirror R']]],
      ['levels', 'Chain levels', [[0, 'trilinear'], [1, 'nearest']]],
      ['bp_diffuse', 'BP diffuse', defines(glsl, 'BP_DIFFUSE')],
    ];
  }

  function buildControls() {
    state.A.irradiance = state.B.irradiance = defaultShKind();
    state.B.so = 4; // IBL_SO_TRIACE_FAST: the comparison `ibl render --compare` shows first
    const rows = $('shading-rows');
    for (const [key, label, options] of variantRows()) {
      const row = document.createElement('div');
      row.className = 'row';
      row.innerHTML = '<span>' + label + '</span>';
      for (const name of ['A', 'B']) {
        const sel = document.createElement('select');
        sel.id = name + '_' + key;
        for (const [value, text] of options) sel.add(new Option(text, value));
        sel.value = state[name][key];
        sel.addEventListener('change', () => { state[name][key] = Number(sel.value); requestDraw(); });
        row.appendChild(sel);
      }
      rows.appendChild(row);
    }
    const bg = $('bg');
    if (hasMirror()) bg.add(new Option('mirror (unfiltered)', -1));
    const pv = probeView();
    for (let k = 0; k < levelCount(); k++) {
      const r = pv.getFloat32(4 * k, true), s = pv.getFloat32(64 + 4 * k, true);
      const size = Math.max(data.textures.specular.width >> k, 1);
      const ggx = (data.manifest.specular || {}).filter === 'ggx';
      bg.add(new Option('level ' + k + ' (' + size + '\u00b2, ' +
                        (ggx ? 'roughness ' + r.toFixed(3) : 'shininess ' + s.toPrecision(4)) + ')', k));
    }
    for (const id of ['scene', 'bg', 'model', 'tonemap'])
      $(id).addEventListener('change', () => { set({ [id]: Number($(id).value) }); });
    for (const id of ['metallic', 'roughness', 'f0', 'shininess', 'ball_ao', 'sphere_ao', 'split_at', 'exposure'])
      $(id).addEventListener('input', () => { set({ [id]: Number($(id).value) }); });
    $('base').addEventListener('input', () => set({ base: $('base').value }));
    $('split').addEventListener('change', () => set({ split: $('split').checked }));
    $('continuous').addEventListener('change', () => set({ continuous: $('continuous').checked }));
    $('reset').addEventListener('click', () => set({ camera: null }));
    syncControls();
  }

  // Shows the state in the controls (after set() from a key, the API or a reset).
  function syncControls() {
    for (const id of ['scene', 'bg', 'model', 'tonemap', 'metallic', 'roughness', 'f0', 'shininess',
                      'ball_ao', 'sphere_ao', 'split_at', 'exposure', 'base'])
      $(id).value = state[id];
    $('split').checked = state.split;
    $('continuous').checked = state.continuous;
    for (const name of ['A', 'B'])
      for (const key of Object.keys(state[name])) {
        const sel = $(name + '_' + key);
        if (sel) sel.value = state[name][key];
      }
    for (const out of document.querySelectorAll('label output')) {
      const input = out.previousElementSibling;
      out.textContent = input.id === 'shininess' ? Math.round(Math.pow(10, Number(input.value)))
                                                 : Number(input.value).toFixed(2);
    }
    for (const el of document.querySelectorAll('.ggx')) el.classList.toggle('hidden', state.model !== 0);
    for (const el of document.querySelectorAll('.bp')) el.classList.toggle('hidden', state.model !== 1);
  }

  // Changes the state (a partial object; A and B merge key by key) and redraws.
  function set(patch) {
    for (const [key, value] of Object.entries(patch)) {
      if (key === 'A' || key === 'B') Object.assign(state[key], value);
      else state[key] = value;
      if (key === 'scene' && !('camera' in patch)) state.camera = null;
      if (key === 'continuous' && value) lastFrame = 0;
    }
    syncControls();
    requestDraw();
  }

  function facts() {
    const m = data.manifest || {}, s = m.specular || {}, rows = [];
    const add = (k, v) => { if (v !== undefined && v !== null && v !== '') rows.push([k, String(v)]); };
    add('generator', m.generator);
    add('source', m.source && m.source.name);
    add('preset', m.parameters && m.parameters.preset);
    add('filter', s.filter);
    add('mapping', s.mapping);
    add('chain', s.size !== undefined && s.size + '\u00b2 \u00d7 ' + s.level_count + ' levels, ' + s.format);
    add('edge fixup', s.edge_fixup);
    add('mirror level', s.mirror);
    if (Array.isArray(s.levels))
      add('levels', s.levels.map((l) => l.roughness !== undefined ? 'r ' + l.roughness : 's ' + l.shininess).join(', '));
    if (m.irradiance) add('irradiance', m.irradiance.size + '\u00b2, ' + m.irradiance.format);
    if (m.sh) add('SH bands', m.sh.bands);
    const b = m.brdf || {};
    const axis = (a) => a ? a.count : '?';
    if (b.splitsum) add('split-sum LUT', axis(b.splitsum.n_dot_v) + '\u00d7' + axis(b.splitsum.roughness));
    if (b.ambient_brdf) add('AmbientBRDF', axis(b.ambient_brdf.n_dot_v) + '\u00d7' + axis(b.ambient_brdf.shininess) + '\u00d7' + axis(b.ambient_brdf.f0));
    // a probe bake (`ibl bake --probes`): the page shows its global probe; list the locals
    const lp = m.probes;
    if (lp && Array.isArray(lp.probes)) {
      add('local probes', lp.count + ' \u00d7 ' + lp.size + '\u00b2 \u00d7 ' + lp.levels + ' levels, ' +
          lp.format + ' (' + lp.array + '; not drawn here)');
      for (const q of lp.probes) add('layer ' + q.layer, q.name);
    }
    const t = m.timings_ms || {};
    if (t.total !== undefined)
      add('bake time', (t.total / 1000).toFixed(2) + ' s (specular ' + (t.specular / 1000).toFixed(2) + ' s)');
    add('viewer', 'WebGL2, ' + (gl.getParameter(gl.VERSION) || ''));
    const table = $('facts');
    for (const [k, v] of rows) {
      const tr = table.insertRow();
      tr.insertCell().textContent = k;
      tr.insertCell().textContent = v;
    }
  }

  // ---- mouse, wheel and keyboard: drag orbits, shift/right drag pans, wheel zooms ----------
  function orbit(dyaw, dpitch) {
    const c = state.camera;
    c.yaw += dyaw;
    c.pitch = Math.max(-1.5, Math.min(1.5, c.pitch + dpitch));
    requestDraw();
  }
  function pan(dx, dy) {
    const c = $('canvas');
    const cam = cameraVectors(state.camera, c.width, c.height);
    const k = 2 * state.camera.dist * cam.tan[1] / c.clientHeight;
    state.camera.target = state.camera.target.map((t, i) => t - k * (dx * cam.right[i] - dy * cam.up[i]));
    requestDraw();
  }
  function zoom(factor) {
    state.camera.dist = Math.max(1.2, Math.min(60, state.camera.dist * factor));
    requestDraw();
  }

  function bindInput() {
    const c = $('canvas');
    let drag = null;
    c.addEventListener('contextmenu', (e) => e.preventDefault());
    c.addEventListener('pointerdown', (e) => {
      c.setPointerCapture(e.pointerId);
      c.focus();
      drag = { x: e.clientX, y: e.clientY, pan: e.button !== 0 || e.shiftKey };
    });
    c.addEventListener('pointermove', (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX;
      drag.y = e.clientY;
      if (drag.pan) pan(dx, dy);
      else orbit(-dx * 0.008, dy * 0.008);
    });
    c.addEventListener('pointerup', () => { drag = null; });
    c.addEventListener('wheel', (e) => { e.preventDefault(); zoom(Math.exp(e.deltaY * 0.001)); }, { passive: false });
    window.addEventListener('keydown', (e) => {
      if (e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT') return;
      const step = 0.05;
      const keys = {
        ArrowLeft: () => e.shiftKey ? pan(20, 0) : orbit(step, 0),
        ArrowRight: () => e.shiftKey ? pan(-20, 0) : orbit(-step, 0),
        ArrowUp: () => e.shiftKey ? pan(0, 20) : orbit(0, -step),
        ArrowDown: () => e.shiftKey ? pan(0, -20) : orbit(0, step),
        '+': () => zoom(0.9), '=': () => zoom(0.9), '-': () => zoom(1 / 0.9),
        r: () => set({ camera: null }), Home: () => set({ camera: null }),
        '1': () => set({ scene: 0 }), '2': () => set({ scene: 1 }),
        s: () => set({ split: !state.split }),
      };
      const f = keys[e.key];
      if (f) {
        e.preventDefault();
        f();
      }
    });
    window.addEventListener('resize', requestDraw);
  }

  // ---- the API -----------------------------------------------------------------------------
  api.state = state;
  api.set = set;
  // Fixes the canvas's size in pixels (null: follow the page) and draws now.
  api.setSize = (w, h) => {
    fixedSize = w ? [w, h] : null;
    const c = $('canvas');
    c.style.width = w ? w + 'px' : '';
    c.style.height = w ? h + 'px' : '';
    drawSynced();
    showStats();
  };
  api.render = () => { drawSynced(); showStats(); };
  // Draws now and returns the canvas's RGBA bytes, top row first, as base64 (mask: white
  // where an object is hit, black elsewhere).
  api.pixels = (mask) => {
    drawSynced(mask ? 2 : 0);
    const c = $('canvas'), w = c.width, h = c.height;
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    const rows = new Uint8Array(w * h * 4);
    for (let y = 0; y < h; y++) rows.set(px.subarray((h - 1 - y) * w * 4, (h - y) * w * 4), y * w * 4);
    let s = '';
    for (let i = 0; i < rows.length; i += 0x8000) s += String.fromCharCode.apply(null, rows.subarray(i, i + 0x8000));
    return { width: w, height: h, data: btoa(s) };
  };
  // Mean milliseconds of `frames` synced draws (after one warm-up frame).
  api.benchmark = (frames) => {
    drawSynced();
    const t0 = performance.now();
    for (let i = 0; i < frames; i++) drawSynced();
    return (performance.now() - t0) / frames;
  };

  try {
    init();
    buildControls();
    facts();
    bindInput();
    api.ready = true;
    requestDraw();
  } catch (e) {
    fail(e.message);
  }
})();
