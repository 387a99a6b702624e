// The scene viewer page's side panel (viewer.js): view buttons, toggles, files, classes and the
// folder's downloadable files. A classic script: it sets window.SceneViewerPanel.
(function () {
    'use strict';

    /// Builds the panel. `ctx`: data, show (toggle states), hiddenClasses, hiddenLayers (sets),
    /// hasEgo, hasImage, drive (or null), setView(name), changed() after every toggle.
    function build(ctx) {
        const { data, show } = ctx;
        const util = window.SceneViewerUtil;
        const checkbox = (parent, text, checked, onChange, colour) =>
            util.checkbox(parent, text, checked, (v) => {
                onChange(v);
                ctx.changed();
            }, colour);
        const views = document.getElementById('views');
        for (const [name, text] of [['camera', 'camera'], ['chase', 'chase'], ['bev', 'BEV']]) {
            const b = document.createElement('button');
            b.textContent = text;
            b.dataset.view = name;
            b.addEventListener('click', () => ctx.setView(name));
            views.appendChild(b);
        }
        const toggles = document.getElementById('toggles');
        checkbox(toggles, 'models', show.models, (v) => { show.models = v; });
        checkbox(toggles, 'boxes', show.boxes, (v) => { show.boxes = v; });
        if (data.cloud) {
            checkbox(toggles, 'point cloud (' + data.cloud.points.toLocaleString('en') + ')',
                     show.cloud, (v) => { show.cloud = v; });
        }
        if (ctx.hasEgo) checkbox(toggles, 'ego car', show.ego, (v) => { show.ego = v; });
        checkbox(toggles, 'grid (BEV)', show.grid, (v) => { show.grid = v; });
        if (ctx.drive && data.drive.trail_frames > 0) {
            checkbox(toggles, 'track trails', true, (v) => ctx.drive.setTrails(v));
        }
        if (ctx.hasImage) {
            checkbox(toggles, 'left image (camera)', show.background,
                     (v) => { show.background = v; });
        }
        if (data.layers.length > 1) {
            document.getElementById('layers-section').hidden = false;
            const layers = document.getElementById('layers');
            data.layers.forEach((layer, i) => {
                checkbox(layers, layer.label + ' (' + layer.entities.length + ')', true,
                         (v) => { if (v) ctx.hiddenLayers.delete(i); else ctx.hiddenLayers.add(i); },
                         layer.colour);
            });
        }
        const classes = document.getElementById('classes');
        for (const c of data.classes) {
            checkbox(classes, c.name, true, (v) => {
                if (v) ctx.hiddenClasses.delete(c.name); else ctx.hiddenClasses.add(c.name);
            }, c.colour);
        }
        const downloads = document.getElementById('downloads');
        const files = [data.scene_file, data.drive && data.drive.models_file,
                       data.cloud && data.cloud.file, data.background_image];
        for (const f of files.filter(Boolean)) {
            const a = document.createElement('a');
            a.href = f;
            a.textContent = f;
            a.download = f;
            downloads.appendChild(a);
        }
    }

    /// Marks the button of the view shown.
    function markView(view) {
        for (const b of document.querySelectorAll('#views button')) {
            b.classList.toggle('active', b.dataset.view === view);
        }
    }

    window.SceneViewerPanel = { build, markView };
})();
