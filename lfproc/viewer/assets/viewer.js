// lfproc viewer: refocus by clicking, move the viewpoint by dragging, read distances in metres.
// Everything this page needs is inline or next to it; it makes no network requests.
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("lfproc-data").textContent);
  var maps = JSON.parse(document.getElementById("lfproc-maps").textContent);
  var $ = function (id) { return document.getElementById(id); };

  function decode(entry) {  // base64 of little-endian bytes -> typed array
    var text = atob(entry.base64), bytes = new Uint8Array(text.length);
    for (var i = 0; i < text.length; i++) { bytes[i] = text.charCodeAt(i); }
    return entry.dtype === "uint8" ? bytes : new Float32Array(bytes.buffer);
  }
  var micro = data.unit === "um";  // a light-field microscope: depths in µm from the native object plane
  var sliceIndex = decode(maps.slice_index), distance = decode(micro ? maps.z_um : maps.distance_mm),
      confidence = decode(maps.confidence);
  var ny = data.lens_shape[0], nx = data.lens_shape[1];
  var apertures = data.apertures && data.apertures.length ? data.apertures : [{ label: "all views", slices: data.slices }];
  var slices = apertures[0].slices, views = data.views.items, centre = data.views.center;

  function metres(mm) {  // as lfproc.outputs.metres: three significant digits
    if (mm === null || mm === undefined || !isFinite(mm)) { return "infinity"; }
    var v = mm / 1000;
    if (Math.abs(v) >= 100) { return v.toFixed(0) + " m"; }
    return (Math.abs(v) >= 1 ? v.toPrecision(3) : v.toFixed(3)) + " m";
  }

  function depthText(v) {  // metres from the sensor, or µm from a microscope's native object plane
    if (!micro) { return metres(v); }
    return (v === null || v === undefined || !isFinite(v)) ? "unknown" : v.toFixed(2) + " µm";
  }
  function at(s) { return micro ? s.z_um : s.distance_mm; }
  // a DOF's ends as people read them: near to far (m from the sensor), low to high z (µm; a microscope's
  // z_near_um, nearer the objective, is the higher number)
  function lowOf(s) { return micro ? Math.min(s.z_near_um, s.z_far_um) : s.near_mm; }
  function highOf(s) { return micro ? Math.max(s.z_near_um, s.z_far_um) : s.far_mm; }
  function dofOf(s) { return micro ? s.dof_um : s.dof_mm; }
  function posOf(v) { return micro ? v.angle_deg : v.position_mm; }

  // ---------------------------------------------------------------- layout
  var photo = $("photo"), depth = $("depth"), slider = $("slider"), marker = $("marker");
  var width = nx * data.display.scale, height = ny * data.display.scale;
  [photo, depth].forEach(function (img) {
    img.width = width; img.height = height;
    // the depth map stays one block per lens whatever the upscaling: an unknown (grey) lens must not blend
    // into its known neighbours, and a click reads the lens under it
    if (data.display.upscale === "nearest" || img === depth) { img.classList.add("pixelated"); }
  });
  $("frame").style.width = width + "px";
  $("title").textContent = "lfproc viewer: " + data.stem;
  $("source").textContent = data.source.split(/[\\/]/).pop();
  $("source").title = data.source;
  if (data.index_href) { $("back").href = data.index_href; $("back").hidden = false; }
  depth.src = data.depth.image;

  // preload every image so that sliding and dragging swap pictures at once
  apertures.reduce(function (all, ap) { return all.concat(ap.slices); }, []).concat(views)
    .forEach(function (item) { new Image().src = item.image; });

  // ---------------------------------------------------------------- state: a slice or a view is shown
  var state = { mode: "slice", slice: 0, view: null };

  function showSlice(k) {
    var s = slices[k];
    state.mode = "slice"; state.slice = k;
    photo.src = s.image;
    photo.dataset.shown = "slice " + k;
    slider.value = String(k);
    $("mode").textContent = "Refocused slice " + (k + 1) + " of " + slices.length + " (a = " + s.a.toFixed(3) + ")";
    $("slice-readout").textContent = "This slice is focused at " + depthText(at(s)) + "; sharp from " +
      depthText(lowOf(s)) + " to " + depthText(highOf(s)) + " (depth of field " +
      (isFinite(dofOf(s)) && dofOf(s) !== null ? depthText(dofOf(s)) : "infinite") + ").";
    $("aperture-readout").textContent = "depth of field " +
      (isFinite(dofOf(s)) && dofOf(s) !== null ? depthText(dofOf(s)) : "infinite") + " (" + depthText(lowOf(s)) +
      " to " + depthText(highOf(s)) + ")";
    drawAperture();
  }

  // ---------------------------------------------------------------- synthetic aperture: the same slices, fewer views
  var apertureSelect = $("aperture-select");
  apertures.forEach(function (ap, i) {
    var option = document.createElement("option");
    option.value = String(i); option.textContent = ap.label;
    apertureSelect.appendChild(option);
  });
  apertureSelect.addEventListener("change", function () {
    slices = apertures[Number(apertureSelect.value)].slices;
    showSlice(state.slice);
  });

  function viewAt(ky, kx) {
    for (var i = 0; i < views.length; i++) {
      if (views[i].view[0] === ky && views[i].view[1] === kx) { return views[i]; }
    }
    return null;
  }

  function nearestView(ky, kx) {  // the view inside the aperture closest to (ky, kx)
    var best = null, bestD = Infinity;
    views.forEach(function (v) {
      var d = (v.view[0] - ky) * (v.view[0] - ky) + (v.view[1] - kx) * (v.view[1] - kx);
      if (d < bestD) { bestD = d; best = v; }
    });
    return best;
  }

  function showView(v) {
    state.mode = "view"; state.view = v;
    photo.src = v.image;
    photo.dataset.shown = "view " + v.view[0] + "," + v.view[1];
    $("mode").textContent = "Viewpoint [" + v.view[0] + ", " + v.view[1] + "] (a view: sharp at every depth)";
    if (micro) {
      $("view-readout").textContent = "View [" + v.view[0] + ", " + v.view[1] + "]: looks into the sample at " +
        v.angle_deg[1].toFixed(2) + "°, " + v.angle_deg[0].toFixed(2) + "° (x, y; sine condition), orthographic.";
      drawAperture();
      return;
    }
    var p = v.position_mm;
    $("view-readout").textContent = "View [" + v.view[0] + ", " + v.view[1] + "]: virtual camera at x = " +
      p[1].toFixed(3) + " mm, y = " + p[0].toFixed(3) + " mm in the main lens focal plane, " +
      v.baseline_to_center_mm.toFixed(3) + " mm from the central view; tilt " + v.tilt_deg[1].toFixed(3) +
      "°, " + v.tilt_deg[0].toFixed(3) + "°. Adjacent views are " + data.views.baseline_mm.toFixed(3) +
      " mm apart.";
    drawAperture();
  }

  // ---------------------------------------------------------------- click: focus where the user points
  function focusAt(jy, jx, fx, fy) {
    var i = jy * nx + jx, k = sliceIndex[i], d = distance[i], c = confidence[i] / 255;
    var out = $("readout");
    out.innerHTML = "";
    marker.hidden = false;
    marker.style.left = (fx * 100) + "%"; marker.style.top = (fy * 100) + "%";
    if (k >= slices.length || isNaN(d)) {  // no depth known here
      var none = document.createElement("b"); none.id = "here-distance"; none.textContent = "unknown";
      out.appendChild(document.createTextNode("Here: ")); out.appendChild(none);
      out.appendChild(document.createTextNode(" (too little texture, or an occlusion edge); the slice stays."));
      out.dataset.distanceMm = "nan"; out.dataset.slice = "";
      return;
    }
    showSlice(k);
    var s = slices[k];
    out.appendChild(document.createTextNode("Here: "));
    var b = document.createElement("b"); b.id = "here-distance"; b.textContent = depthText(d); out.appendChild(b);
    out.appendChild(document.createTextNode((micro ? " from the native object plane" : " from the sensor") +
      (c < data.depth.min_confidence ? " (low confidence: little texture here)" : "") + ". Sharpest slice: " +
      depthText(at(s)) + ", in focus from " + depthText(lowOf(s)) + " to " + depthText(highOf(s)) + "."));
    out.dataset.distanceMm = isFinite(d) ? String(d) : "inf";
    out.dataset.slice = String(k);
  }

  function lensOf(img, event) {
    var r = img.getBoundingClientRect();
    var fx = (event.clientX - r.left) / r.width, fy = (event.clientY - r.top) / r.height;
    fx = Math.min(Math.max(fx, 0), 0.999999); fy = Math.min(Math.max(fy, 0), 0.999999);
    return { jy: Math.floor(fy * ny), jx: Math.floor(fx * nx), fx: fx, fy: fy };
  }

  // ---------------------------------------------------------------- drag: move the viewpoint
  var drag = null;
  photo.addEventListener("pointerdown", function (e) {
    e.preventDefault();
    var start = state.view || viewAt(centre, centre) || nearestView(centre, centre);
    drag = { x: e.clientX, y: e.clientY, moved: false, start: start };
    photo.setPointerCapture(e.pointerId);
  });
  photo.addEventListener("pointermove", function (e) {
    if (!drag) { return; }
    var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (!drag.moved && Math.abs(dx) + Math.abs(dy) < 6) { return; }
    drag.moved = true;
    var r = photo.getBoundingClientRect(), m = data.views.m_hat;  // the picture's width spans all views
    var v = nearestView(drag.start.view[0] + Math.round(dy / r.height * m),
                        drag.start.view[1] + Math.round(dx / r.width * m));
    if (v && v !== state.view) { showView(v); }
  });
  photo.addEventListener("pointerup", function (e) {
    if (drag && !drag.moved) { var p = lensOf(photo, e); focusAt(p.jy, p.jx, p.fx, p.fy); }
    drag = null;
  });
  photo.addEventListener("pointercancel", function () { drag = null; });
  depth.addEventListener("click", function (e) { var p = lensOf(depth, e); focusAt(p.jy, p.jx, p.fx, p.fy); });

  document.addEventListener("keydown", function (e) {
    var steps = { ArrowLeft: [0, -1], ArrowRight: [0, 1], ArrowUp: [-1, 0], ArrowDown: [1, 0] }[e.key];
    if (!steps || e.target === slider || e.target === apertureSelect) { return; }
    e.preventDefault();
    var from = state.view || viewAt(centre, centre) || nearestView(centre, centre);
    var next = viewAt(from.view[0] + steps[0], from.view[1] + steps[1]);
    if (next) { showView(next); } else if (state.mode !== "view") { showView(from); }
  });

  // ---------------------------------------------------------------- slider over the slices, in metres
  slider.max = String(slices.length - 1);
  slider.addEventListener("input", function () { showSlice(Number(slider.value)); });
  // a camera's slices read near (left) to far like every range on the page; a microscope's low to high z
  if (!micro) { slider.style.direction = "rtl"; }
  var labels = $("slider-labels"), every = Math.max(1, Math.ceil(slices.length / 6));
  var order = slices.map(function (s, k) { return k; });
  if (!micro) { order.reverse(); }
  order.forEach(function (k) {
    if (k % every !== 0 && k !== slices.length - 1) { return; }
    var span = document.createElement("span"), place = slices.length > 1 ? k / (slices.length - 1) : 0.5;
    span.textContent = depthText(at(slices[k]));
    span.style.left = ((micro ? place : 1 - place) * 100) + "%";
    labels.appendChild(span);
  });

  // ---------------------------------------------------------------- the views in the aperture, with the baseline
  var svgNS = "http://www.w3.org/2000/svg";  // an XML namespace name, not a network request
  function drawAperture() {
    var svg = $("aperture"), radius = micro ? data.views.aperture_radius_deg : data.views.aperture_radius_mm, reach = 0;
    views.forEach(function (v) { reach = Math.max(reach, Math.abs(posOf(v)[0]), Math.abs(posOf(v)[1])); });
    var scale = 1 / Math.max(radius || 0, reach * 1.05, 1e-9);
    svg.innerHTML = "";
    if (radius) {
      var stop = document.createElementNS(svgNS, "circle");
      stop.setAttribute("class", "stop"); stop.setAttribute("r", String(radius * scale));
      svg.appendChild(stop);
    }
    var dot = 0.45 * (micro ? data.views.angle_step_deg : data.views.baseline_mm) * scale;
    views.forEach(function (v) {
      var c = document.createElementNS(svgNS, "circle");
      c.setAttribute("class", "view" + (state.mode === "view" && state.view === v ? " current" : ""));
      // each view's virtual camera as the pictures show it (marker_mm: position_mm, or a microscope's angle_deg,
      // through the inverting optics)
      var where = v.marker_mm || posOf(v);
      c.setAttribute("cx", String(where[1] * scale)); c.setAttribute("cy", String(where[0] * scale));
      c.dataset.view = v.view[0] + "," + v.view[1];
      c.setAttribute("r", String(dot));
      c.addEventListener("click", function () { showView(v); });
      var title = document.createElementNS(svgNS, "title");
      title.textContent = "view [" + v.view + "], " + (micro ? posOf(v).map(function (x) { return x.toFixed(1); })
        .join("°, ") + "° in the sample" : v.baseline_to_center_mm.toFixed(3) + " mm from the centre");
      c.appendChild(title);
      svg.appendChild(c);
    });
  }

  // ---------------------------------------------------------------- depth legend and summaries
  var colours = data.depth.colours.map(function (c) { return "rgb(" + c.join(",") + ")"; });
  // read as people read ranges: a camera's near (left) to far, a microscope's low z (left) to high z
  $("legend-bar").style.background = "linear-gradient(to " + (micro ? "right" : "left") + ", " +
    colours.join(", ") + ")";
  data.depth.ticks.slice().sort(function (p, q) { return micro ? p.t - q.t : q.t - p.t; }).forEach(function (t) {
    var span = document.createElement("span");
    span.textContent = depthText(micro ? t.z_um : t.distance_mm);
    span.style.left = ((micro ? t.t : 1 - t.t) * 100) + "%";
    $("legend-ticks").appendChild(span);
  });

  // tick labels never overlap or leave the legend: both ends always, an inner label only where it fits
  function layoutTicks() {
    var spans = Array.prototype.slice.call($("legend-ticks").children), kept = [], gap = 6;
    var box = $("legend-ticks").getBoundingClientRect();
    var order = spans.length > 1 ? [0, spans.length - 1] : [0];
    for (var i = 1; i < spans.length - 1; i++) { order.push(i); }
    order.forEach(function (i) {
      var span = spans[i];
      span.style.visibility = "visible";
      var r = span.getBoundingClientRect();
      var clash = kept.some(function (k) { return r.left < k.right + gap && k.left < r.right + gap; }) ||
        r.left < box.left - 0.5 || r.right > box.right + 0.5;
      if (clash && kept.length) { span.style.visibility = "hidden"; } else { kept.push(r); }
    });
  }
  layoutTicks();
  window.addEventListener("resize", layoutTicks);
  $("depth-method").textContent = (micro ? "Depth from the native object plane (towards the objective: +), " :
    "Distance from the sensor, ") + data.depth.method + "; colours " +
    data.depth.colour_scale + ".";

  function fillTable(table, rows) {
    rows.forEach(function (row) {
      var tr = document.createElement("tr");
      row.forEach(function (cell) { var td = document.createElement("td"); td.textContent = String(cell); tr.appendChild(td); });
      table.appendChild(tr);
    });
  }
  fillTable($("camera"), data.camera);
  var calib = Object.keys(data.calibration).map(function (k) { return [k.replace(/_/g, " "), data.calibration[k]]; });
  fillTable($("calibration"), calib.length ? calib : [["grid", "not recorded"]]);
  $("display").textContent = "Images are 8-bit sRGB previews, enlarged " + data.display.scale + "x (" +
    data.display.upscale + "); exposure: " + data.display.tone_map.description + ". The linear TIFF/EXR " +
    "outputs of lfproc refocus and lfproc views are the data.";

  // start on the slice sharpest at the centre of the picture
  var middle = Math.floor(ny / 2) * nx + Math.floor(nx / 2);
  showSlice(sliceIndex[middle] < slices.length ? sliceIndex[middle] : Math.floor(slices.length / 2));
  document.body.dataset.ready = "true";
})();
