// Helpers of the scene viewer page (viewer.js) that need none of its state: the WebGL probe,
// base64 decoding, the details pane's rows, the panel's checkboxes, the BEV framing, the orbit
// benchmark and the pace of the moving level of detail. A classic script: it sets
// window.SceneViewerUtil before viewer.js runs.
(function () {
    'use strict';

    /// True on a software WebGL (SwiftShader, llvmpipe), where multisampling halves the frame rate.
    function softwareWebgl() {
        const probe = document.createElement('canvas').getContext('webgl2');
        if (!probe) return false;
        const info = probe.getExtension('WEBGL_debug_renderer_info');
        const name = info ? String(probe.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
        const lose = probe.getExtension('WEBGL_lose_context');
        if (lose) lose.loseContext();
        return /swiftshader|llvmpipe|softpipe/i.test(name);
    }

    function decodeBase64(text) {
        if (Uint8Array.fromBase64) return Uint8Array.fromBase64(text).buffer;
        const binary = atob(text);
        const bytes = new Uint8Array(binary.length);
        for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
        return bytes.buffer;
    }

    function fmt(v, digits) {
        return typeof v === 'number' ? v.toFixed(digits) : String(v);
    }

    /// The details pane's rows of an entity: [label, text] pairs, in the entity file's frame
    /// and units (metres, radians shown in degrees too).
    function detailRows(e) {
        const rows = [
            ['id', e.id],
            ['class', e.class + ' (' + e.class_id + ')'],
            ['x, y, z', [e.x, e.y, e.z].map((v) => fmt(v, 2)).join(', ') + ' m'],
            ['heading', fmt(e.theta * 180 / Math.PI, 1) + '° (' + fmt(e.theta, 3) + ' rad)'],
            ['W × H × L', [e.W, e.H, e.L].map((v) => fmt(v, 2)).join(' × ') + ' m'],
            ['confidence', fmt(e.confidence, 2)],
            ['points', e.point_count],
        ];
        if (e.method) rows.push(['method', e.method]);
        for (const key of ['track_id', 'track']) if (e[key] !== undefined) rows.push(['track', e[key]]);
        if (e.velocity) {
            const { vx, vz } = e.velocity;
            rows.push(['velocity', fmt(vx, 2) + ', ' + fmt(vz, 2) + ' m/s (speed ' +
                       fmt(Math.hypot(vx, vz), 2) + ' m/s)']);
        }
        for (const key of ['speed_mps', 'speed']) {
            if (e[key] !== undefined) rows.push(['speed', fmt(e[key], 2) + ' m/s']);
        }
        return rows;
    }

    /// A labelled checkbox (with a colour swatch when `colour` is given) appended to `parent`;
    /// onChange(checked) runs on every change.
    function checkbox(parent, text, checked, onChange, colour) {
        const label = document.createElement('label');
        const input = document.createElement('input');
        input.type = 'checkbox';
        input.checked = checked;
        input.addEventListener('change', () => {
            onChange(input.checked);
        });
        label.appendChild(input);
        if (colour) {
            const swatch = document.createElement('span');
            swatch.className = 'swatch';
            swatch.style.background = colour;
            label.appendChild(swatch);
        }
        label.appendChild(document.createTextNode(text));
        parent.appendChild(label);
        return input;
    }

    /// The BEV framing of views.cpp's bev_view_fitting over every file's footprints (a drive:
    /// over every frame's, from the data's extent).
    function bevFit(data, aspect) {
        let minX = -2, maxX = 2, minZ = -4, maxZ = 4;
        if (data.drive) [minX, maxX, minZ, maxZ] = data.drive.extent;
        for (const layer of data.drive ? [] : data.layers) {
            for (const e of layer.entities) {
                const r = 0.5 * Math.hypot(e.W, e.L);
                minX = Math.min(minX, e.x - r);
                maxX = Math.max(maxX, e.x + r);
                minZ = Math.min(minZ, e.z - r);
                maxZ = Math.max(maxZ, e.z + r);
            }
        }
        const halfH = 0.5 * (maxZ - minZ);
        const halfW = 0.5 * (maxX - minX);
        return {
            centre: [0.5 * (minX + maxX), 0.5 * (minZ + maxZ)],
            halfHeight: data.views.bev.margin * Math.max(halfH, halfW / aspect),
            halfWidth: halfW, halfDepth: halfH,
        };
    }

    /// Orbits `controls` for `ms` milliseconds and reports the frame rate seen by
    /// requestAnimationFrame.
    function orbitBenchmark(controls, ms) {
        return new Promise((resolve) => {
            controls.autoRotate = true;
            controls.autoRotateSpeed = 30;
            const times = [];
            function tick(t) {
                times.push(t);
                if (t - times[0] < ms) {
                    requestAnimationFrame(tick);
                    return;
                }
                controls.autoRotate = false;
                const span = times[times.length - 1] - times[0];
                let worst = 0;
                for (let i = 1; i < times.length; ++i) worst = Math.max(worst, times[i] - times[i - 1]);
                resolve({ frames: times.length - 1, fps: (times.length - 1) * 1000 / span,
                          worst_ms: worst });
            }
            requestAnimationFrame(tick);
        });
    }

    /// Detail drawn while the view moves, lowered one level after every 10 moving frames whose
    /// smoothed interval is over 34 ms (under 30 fps): `pixels` is the share of the full pixel
    /// ratio, `points` of the cloud's moving sample. drawn(moving, now) after every frame.
    const kMovingLevels = [[1, 1], [0.75, 1], [0.5, 1], [0.5, 0.5], [0.5, 0.25]];
    function movingPace() {
        let last = null, interval = 0, frames = 0, level = 0;
        const pace = {
            pixels: 1,
            points: 1,
            drawn(moving, now) {
                if (!moving) {
                    last = null;
                    return;
                }
                if (last !== null) {
                    interval = frames ? 0.8 * interval + 0.2 * (now - last) : now - last;
                    if (++frames >= 10 && interval > 34 && level + 1 < kMovingLevels.length) {
                        [pace.pixels, pace.points] = kMovingLevels[++level];
                        frames = 0;
                    }
                }
                last = now;
            },
        };
        return pace;
    }

    window.SceneViewerUtil = {
        softwareWebgl, decodeBase64, fmt, detailRows, checkbox, bevFit, orbitBenchmark, movingPace,
    };
})();
