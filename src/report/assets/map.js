/* skytie report: the interactive trajectory map (pan/zoom with Leaflet, CRS.Simple in the campaign's projected
 * metres). One canvas layer draws everything in one pass, so 10^4 recordings stay responsive. Data come from
 * window.SKYTIE_MAPS[id], written by the report next to this file (columnar arrays, coordinates relative to
 * `origin`). Clicking a recording shows its numbers and registration views in the panel beside the map;
 * the page address `#select=<image_id>` does the same on load. */
(function () {
  'use strict';
  var SUPPORT = [
    ['controlled', '#0072B2', 'corrected by aerial control points it observes itself'],
    ['bridged', '#009E73', 'no control point of its own; corrected through neighbours with control on both sides'],
    ['extrapolated', '#E69F00', 'no control point of its own; corrected through neighbours with control on one side only'],
    ['uncorrected', '#D55E00', 'not corrected: no aerial control point is linked to its stretch of trajectory']
  ];
  var STATUS = { pass: '#009E73', fail: '#D55E00', insufficient: '#999999' };

  function nice(v) {
    if (!(v > 0)) { return 1; }
    var e = Math.pow(10, Math.floor(Math.log(v) / Math.LN10));
    var f = v / e;
    return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * e;
  }

  function fmt(v, digits) {
    return (v === null || v === undefined || isNaN(v)) ? 'n/a' : Number(v).toFixed(digits);
  }

  function esc(s) {
    return String(s).replace(/[&<>"']/g, function (c) {
      return { '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' }[c];
    });
  }

  var DataLayer = L.Layer.extend({
    initialize: function (d, state) { this._d = d; this._s = state; },
    onAdd: function (map) {
      this._map = map;
      this._canvas = L.DomUtil.create('canvas', 'skytie-map-canvas');
      map.getPanes().overlayPane.appendChild(this._canvas);
      map.on('moveend zoomend resize viewreset', this.redraw, this);
      this.redraw();
    },
    onRemove: function (map) {
      L.DomUtil.remove(this._canvas);
      map.off('moveend zoomend resize viewreset', this.redraw, this);
    },
    point: function (x, y) { return this._map.latLngToContainerPoint([y, x]); },
    redraw: function () {
      var t0 = performance.now();
      var map = this._map, d = this._d, s = this._s, R = d.recordings;
      var size = map.getSize(), ratio = window.devicePixelRatio || 1;
      var c = this._canvas;
      L.DomUtil.setPosition(c, map.containerPointToLayerPoint([0, 0]));
      c.width = size.x * ratio; c.height = size.y * ratio;
      c.style.width = size.x + 'px'; c.style.height = size.y + 'px';
      var g = c.getContext('2d');
      g.setTransform(ratio, 0, 0, ratio, 0, 0);
      g.clearRect(0, 0, size.x, size.y);
      var n = R.id.length, i, p, q, drawn = 0;
      var E = s.exaggeration;
      if (s.show.segments) {
        g.lineWidth = 7; g.lineCap = 'round'; g.globalAlpha = 0.35;
        d.segments.forEach(function (seg) {
          if (seg.trajectory !== s.segmentTrajectory) { return; }
          g.strokeStyle = STATUS[seg.status] || '#999999';
          var xs = seg.trajectory === 'recorded' ? R.rx : R.ax, ys = seg.trajectory === 'recorded' ? R.ry : R.ay;
          g.beginPath();
          for (i = seg.from; i <= seg.to; i++) {
            p = this.point(xs[i], ys[i]);
            if (i === seg.from) { g.moveTo(p.x, p.y); } else { g.lineTo(p.x, p.y); }
          }
          g.stroke();
        }, this);
        g.globalAlpha = 1;
      }
      if (s.show.vectors) {
        g.lineWidth = 1.5; g.strokeStyle = '#333333';
        g.beginPath();
        for (i = 0; i < n; i++) {
          p = this.point(R.rx[i], R.ry[i]);
          q = this.point(R.rx[i] + E * (R.ax[i] - R.rx[i]), R.ry[i] + E * (R.ay[i] - R.ry[i]));
          g.moveTo(p.x, p.y); g.lineTo(q.x, q.y);
        }
        g.stroke();
      }
      if (s.show.recorded) {
        g.strokeStyle = '#777777'; g.lineWidth = 1;
        g.beginPath();
        for (i = 0; i < n; i++) {
          p = this.point(R.rx[i], R.ry[i]);
          g.moveTo(p.x + 3, p.y); g.arc(p.x, p.y, 3, 0, 2 * Math.PI);
        }
        g.stroke();
      }
      if (s.show.adjusted) {
        for (var k = 0; k < SUPPORT.length; k++) {
          g.fillStyle = SUPPORT[k][1];
          g.beginPath();
          for (i = 0; i < n; i++) {
            if (R.support[i] !== k) { continue; }
            p = this.point(R.ax[i], R.ay[i]);
            if (p.x < -10 || p.y < -10 || p.x > size.x + 10 || p.y > size.y + 10) { continue; }
            g.moveTo(p.x + 4, p.y); g.arc(p.x, p.y, 4, 0, 2 * Math.PI);
            drawn++;
          }
          g.fill();
        }
      }
      var C = d.control;
      if (s.show.control && C) {
        g.fillStyle = '#CC79A7';
        g.beginPath();
        for (i = 0; i < C.x.length; i++) {
          p = this.point(C.x[i], C.y[i]);
          g.moveTo(p.x + 2, p.y); g.arc(p.x, p.y, 2, 0, 2 * Math.PI);
        }
        g.fill();
      }
      var K = d.checkpoints;
      if (s.show.checkpoints && K) {
        for (i = 0; i < K.id.length; i++) {
          p = this.point(K.x[i], K.y[i]);
          g.fillStyle = '#000000';
          g.fillRect(p.x - 3.5, p.y - 3.5, 7, 7);
          [[K.bx, K.by, '#888888'], [K.ax, K.ay, '#D55E00']].forEach(function (e) {
            if (e[0][i] === null) { return; }
            q = this.point(K.x[i] + E * e[0][i], K.y[i] + E * e[1][i]);
            g.strokeStyle = e[2]; g.lineWidth = 2;
            g.beginPath(); g.moveTo(p.x, p.y); g.lineTo(q.x, q.y); g.stroke();
          }, this);
        }
      }
      if (s.selected !== null) {
        p = this.point(R.ax[s.selected], R.ay[s.selected]);
        g.strokeStyle = '#000000'; g.lineWidth = 2.5;
        g.beginPath(); g.arc(p.x, p.y, 9, 0, 2 * Math.PI); g.stroke();
      }
      var el = map.getContainer();
      el.setAttribute('data-drawn', drawn);
      el.setAttribute('data-redraw-ms', (performance.now() - t0).toFixed(1));
    }
  });

  /* The bar that shows how long a correction of X m is drawn at the current zoom. */
  var VectorScale = L.Control.extend({
    options: { position: 'bottomleft' },
    initialize: function (state) { this._s = state; },
    onAdd: function (map) {
      this._div = L.DomUtil.create('div', 'skytie-vector-scale');
      map.on('zoomend', this.update, this);
      this.update();
      return this._div;
    },
    update: function () {
      var map = this._map;
      if (!map) { return; }
      var pxPerMetre = map.options.crs.scale(map.getZoom());
      var metres = nice(90 / (pxPerMetre * this._s.exaggeration));
      var width = Math.round(metres * this._s.exaggeration * pxPerMetre);
      this._div.innerHTML = '<div class="bar" style="width:' + width + 'px"></div>correction vectors ×' +
        this._s.exaggeration + ': bar = ' + metres + ' m';
    }
  });

  function panel(d, i, el) {
    var R = d.recordings;
    var sup = SUPPORT[R.support[i]];
    var dx = R.ax[i] - R.rx[i], dy = R.ay[i] - R.ry[i];
    var rows = [
      ['time', esc(R.time[i])],
      ['correction', '<span style="color:' + sup[1] + '">' + esc(sup[0]) + '</span>: ' + esc(sup[2])],
      ['aerial control points observed', R.control[i]],
      ['moved (adjusted − recorded) E, N, U', fmt(dx, 3) + ', ' + fmt(dy, 3) + ', ' + fmt(R.dz[i], 3) + ' m'],
      ['moved horizontally', fmt(Math.sqrt(dx * dx + dy * dy), 3) + ' m'],
      ['yaw correction', fmt(R.dyaw[i], 4) + '°'],
      ['σ after (E, N, U)', fmt(R.sx[i], 3) + ', ' + fmt(R.sy[i], 3) + ', ' + fmt(R.sz[i], 3) + ' m'],
      ['verification of its segment, recorded poses', esc(R.before[i] || 'n/a')],
      ['verification of its segment, adjusted poses', esc(R.after[i] || 'n/a')]
    ];
    var h = '<h3>' + esc(R.id[i]) + '</h3><table>';
    rows.forEach(function (r) { h += '<tr><th>' + r[0] + '</th><td>' + r[1] + '</td></tr>'; });
    h += '</table>';
    var views = (d.views || {})[R.id[i]] || [];
    if (views.length === 0) {
      h += '<p class="note">No registration view of this recording in the report (the report draws views for the ' +
        'recordings with the most control points; <code>skytie report OUT --views N</code> draws more).</p>';
    }
    views.forEach(function (v) {
      h += '<figure><img src="' + esc(v[0]) + '" alt="registration view"><figcaption>' + esc(v[1]) +
        '</figcaption></figure>';
    });
    el.innerHTML = h;
    el.setAttribute('data-selected', R.id[i]);
  }

  function initMap(id) {
    var t0 = performance.now();
    var d = window.SKYTIE_MAPS[id];
    var el = document.getElementById('map-' + id);
    var side = document.getElementById('panel-' + id);
    var R = d.recordings, n = R.id.length;
    var map = L.map(el, {
      crs: L.CRS.Simple, minZoom: -10, maxZoom: 9, zoomSnap: 0.25, zoomDelta: 0.5,
      zoomAnimation: false, attributionControl: false
    });
    var state = {
      exaggeration: d.exaggeration, selected: null,
      segmentTrajectory: d.segments.some(function (s) { return s.trajectory === 'adjusted'; }) ? 'adjusted' : 'recorded',
      show: { segments: true, vectors: true, recorded: true, adjusted: true, control: true, checkpoints: true }
    };
    var lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
    for (var i = 0; i < n; i++) {
      [[R.rx[i], R.ry[i]], [R.ax[i], R.ay[i]]].forEach(function (p) {
        lo = [Math.min(lo[0], p[0]), Math.min(lo[1], p[1])];
        hi = [Math.max(hi[0], p[0]), Math.max(hi[1], p[1])];
      });
    }
    var backgrounds = (d.backgrounds || []).map(function (b) {
      return L.imageOverlay(b.href, [[b.y0, b.x0], [b.y1, b.x1]], { opacity: 0.85 }).addTo(map);
    });
    map.fitBounds([[lo[1] - 10, lo[0] - 10], [hi[1] + 10, hi[0] + 10]]);
    var layer = new DataLayer(d, state);
    layer.addTo(map);
    L.control.scale({ imperial: false, maxWidth: 160 }).addTo(map);
    new VectorScale(state).addTo(map);
    var toggles = L.control({ position: 'topright' });
    toggles.onAdd = function () {
      var div = L.DomUtil.create('div', 'skytie-toggles');
      var items = [['adjusted', 'adjusted positions'], ['recorded', 'recorded positions'],
        ['vectors', 'correction vectors'], ['segments', 'verification per segment'],
        ['control', 'aerial control points'], ['checkpoints', 'check points']];
      var h = items.map(function (it) {
        return '<label><input type="checkbox" data-key="' + it[0] + '" checked> ' + it[1] + '</label>';
      }).join('<br>');
      if (backgrounds.length) { h += '<br><label><input type="checkbox" data-key="background" checked> nadir image</label>'; }
      div.innerHTML = h;
      L.DomEvent.disableClickPropagation(div);
      div.addEventListener('change', function (e) {
        var key = e.target.getAttribute('data-key');
        if (key === 'background') {
          backgrounds.forEach(function (b) { if (e.target.checked) { b.addTo(map); } else { b.remove(); } });
        } else {
          state.show[key] = e.target.checked;
          layer.redraw();
        }
      });
      return div;
    };
    toggles.addTo(map);
    function select(i) {
      state.selected = i;
      panel(d, i, side);
      layer.redraw();
    }
    map.on('click', function (e) {
      var best = null, bestD = 12 * 12;
      for (var i = 0; i < n; i++) {
        var p = map.latLngToContainerPoint([R.ay[i], R.ax[i]]);
        var dd = (p.x - e.containerPoint.x) * (p.x - e.containerPoint.x) + (p.y - e.containerPoint.y) * (p.y - e.containerPoint.y);
        if (dd < bestD) { bestD = dd; best = i; }
      }
      if (best !== null) { select(best); }
    });
    var m = /select=([^&]+)/.exec(window.location.hash);
    if (m) {
      var want = decodeURIComponent(m[1]), k = R.id.indexOf(want);
      if (k >= 0) { select(k); map.setView([R.ay[k], R.ax[k]], Math.max(map.getZoom(), 2)); }
    }
    el.setAttribute('data-recordings', n);
    el.setAttribute('data-init-ms', (performance.now() - t0).toFixed(1));
    el.setAttribute('data-ready', '1');
  }

  window.addEventListener('load', function () {
    Object.keys(window.SKYTIE_MAPS || {}).forEach(initMap);
  });
})();
