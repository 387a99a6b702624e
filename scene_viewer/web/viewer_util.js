// Helpers of the scene viewer page (viewer.js) that need none of its state: the WebGL probe,
// base64 decoding, the details pane's rows and the panel's checkboxes. A classic script: it
// sets window.SceneViewerUtil before viewer.js runs.
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

    window.SceneViewerUtil = { softwareWebgl, decodeBase64, fmt, detailRows, checkbox };
})();
