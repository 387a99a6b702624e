// The scene viewer page (docs/viewer.md): a classic script over the global THREE of
// three.min.js and the data scripts scene-render html writes (window.SCENE_VIEWER_DATA and the
// base64 .glb files in window.SCENE_VIEWER_BLOBS). Coordinates are glTF/OpenGL (x right, y up,
// z backward, metres); the details pane shows the entity file's KITTI camera frame values.
(function () {
    'use strict';

    const data = window.SCENE_VIEWER_DATA;
    const util = window.SceneViewerUtil;
    const params = new URLSearchParams(window.location.search);
    const statusBox = document.getElementById('status');
    const canvas = document.getElementById('view');
    const backgroundImg = document.getElementById('background');
    const detailsBox = document.getElementById('details');

    let resolveReady;
    let rejectReady;
    const api = {
        ready: new Promise((resolve, reject) => {
            resolveReady = resolve;
            rejectReady = reject;
        }),
        firstFrameMs: null,  // performance.now() at the first frame
        cloudFrameMs: null,  // ... at the first frame with the cloud (its sample)
        fullFrameMs: null,   // ... at the first frame with every cloud point
        view: 'camera',
        frames: 0,
        timings: {},  // performance.now() at each loading step
    };
    const mark = (name) => { api.timings[name] = performance.now(); };
    mark('scripts');
    window.viewer = api;
    if (params.get('ui') === '0') document.body.classList.add('no-ui');

    const show = {
        cloud: true, ego: true, grid: true, background: true, models: true, boxes: false,
    };
    const hiddenClasses = new Set();
    const hiddenLayers = new Set();

    const renderer = new THREE.WebGLRenderer({ canvas, antialias: !util.softwareWebgl(), alpha: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    const scene = new THREE.Scene();
    const perspective = new THREE.PerspectiveCamera(60, 1, data.views.camera.near,
                                                    data.views.camera.far);
    const orthographic = new THREE.OrthographicCamera(-1, 1, 1, -1, 1, 2 * data.views.bev.height_m);
    let camera = perspective;
    let controls = null;
    let dirty = true;
    let lastMotion = -Infinity;  // performance.now() of the last moving frame
    let coarse = false;          // drawing the cloud's moving_points sample

    const entityObjects = [];  // {layer, entity, object} of every drawn entity
    const egoObjects = [];
    const cloudObjects = [];   // {className, object}
    let grid = null;
    let highlight = null;
    let pinned = null;
    let drive = null;  // the drive controller (viewer_drive.js) when the page shows a drive

    const classById = new Map(data.classes.map((c) => [c.id, c]));
    const hasImage = !!data.background_image || !!(data.drive && data.drive.frames.some((f) => f.image));

    function setStatus(text, isError) {
        statusBox.textContent = text;
        statusBox.classList.toggle('error', !!isError);
    }

    function parseGlb(name) {
        const blobs = window.SCENE_VIEWER_BLOBS || {};
        if (!(name in blobs)) return Promise.reject(new Error('missing data for ' + name));
        const loader = new THREE.GLTFLoader();
        const bytes = util.decodeBase64(blobs[name]);
        delete blobs[name];  // the page keeps the geometry, not the text
        return new Promise((resolve, reject) => loader.parse(bytes, '', resolve, reject));
    }

    /// Resolves once the deferred cloud script has run (file:// pages cannot fetch it).
    function cloudScriptLoaded() {
        return new Promise((resolve, reject) => {
            const blobs = window.SCENE_VIEWER_BLOBS || {};
            const tag = document.getElementById('cloud-data');
            if (data.cloud.file in blobs || !tag) {
                resolve();
                return;
            }
            tag.addEventListener('load', () => resolve());
            tag.addEventListener('error', () => reject(new Error('cannot load data/cloud-glb.js')));
        });
    }

    // --- lights: the renderer's lit shading, c * (ambient + (1 - ambient) * max(n.l, 0)) ---
    function addLights() {
        const a = data.light.ambient;
        scene.add(new THREE.AmbientLight(0xffffff, a * Math.PI));
        const sun = new THREE.DirectionalLight(0xffffff, (1 - a) * Math.PI);
        sun.position.fromArray(data.light.direction);
        scene.add(sun);
    }

    /// Lambert materials (no specular): closer to scene-render's lighting and cheaper. One per
    /// source material, so copies of a model keep sharing theirs (and draw as instances).
    const lambertOf = new Map();
    function toLambert(material) {
        if (lambertOf.has(material.uuid)) return lambertOf.get(material.uuid);
        const m = new THREE.MeshLambertMaterial({
            color: material.color, map: material.map || null, side: material.side,
            transparent: material.transparent, opacity: material.opacity,
        });
        m.name = material.name;
        lambertOf.set(material.uuid, m);
        return m;
    }

    /// Draws the entities' class models as instances (viewer_models.js): `entries` are
    /// {entity, root} with root placed in the world frame; replaces the models drawn before.
    let models = null;
    function setModels(entries) {
        if (models) scene.remove(models.group);
        const items = entries.map(({ entity }) => {
            const item = { layer: 0, entity, object: new THREE.Object3D(), kind: 'model' };
            entityObjects.push(item);
            return item;
        });
        models = window.SceneViewerModels.create(
            entries.map(({ root }, i) => ({ item: items[i], root })));
        scene.add(models.group);
    }

    // --- the scene: the first file's models, from scene.glb ---
    function addSceneModels(gltf) {
        // Nodes are the scene's roots, named by entity id (three.js keeps the raw name in
        // userData.name and a sanitised one in name).
        const byId = new Map();
        for (const e of data.layers[0].entities) {
            byId.set(e.id, e);
            byId.set(THREE.PropertyBinding.sanitizeNodeName(e.id), e);
        }
        gltf.scene.traverse((object) => {
            if (!object.isMesh) return;
            const materials = Array.isArray(object.material) ? object.material : [object.material];
            const lambert = materials.map(toLambert);
            object.material = Array.isArray(object.material) ? lambert : lambert[0];
        });
        const groundClasses = new Set(data.classes.filter((c) => c.ground).map((c) => c.name));
        const placed = [];
        for (const object of [...gltf.scene.children]) {
            const name = object.userData.name !== undefined ? object.userData.name : object.name;
            const entity = byId.get(name) || byId.get(object.name);
            if (entity && !groundClasses.has(entity.class)) {
                gltf.scene.remove(object);
                placed.push({ entity, root: object });
            } else if (entity) {
                paintFirst(object);
                entityObjects.push({ layer: 0, entity, object, kind: 'model' });
            } else if (name === 'ego') {
                egoObjects.push(object);
            }
        }
        scene.add(gltf.scene);
        setModels(placed);
    }

    /// Ground patches are painted first and write no depth, so whatever stands on them covers
    /// them. Depth alone is not enough: on SwiftShader (software WebGL) a patch that reaches
    /// closer than the near plane (a road starting at the camera, z = 0) gets wrong depths and
    /// is drawn over the cars.
    function paintFirst(object) {
        object.traverse((o) => {
            if (!o.isMesh) return;
            o.renderOrder = -1;
            for (const m of Array.isArray(o.material) ? o.material : [o.material]) m.depthWrite = false;
        });
    }

    // --- every file's entities as boxes in the file's colour (the comparison overlay) ---
    const unitBox = new THREE.BoxGeometry(1, 1, 1);
    const unitEdges = new THREE.EdgesGeometry(unitBox);

    function placeBox(object, e) {
        object.position.set(e.x, -e.y, -e.z);
        object.rotation.set(0, Math.PI / 2 - e.theta, 0);
        object.scale.set(e.W, e.H, e.L);
    }

    const boxMaterials = data.layers.map((layer) => {
        const colour = new THREE.Color(layer.colour);
        return {
            edges: new THREE.LineBasicMaterial({ color: colour }),
            faces: new THREE.MeshBasicMaterial({
                color: colour, transparent: true, opacity: 0.15, depthWrite: false,
            }),
        };
    });

    /// The entity's box in its file's colour: edges and translucent faces.
    function boxOf(layer, e) {
        const group = new THREE.Group();
        group.add(new THREE.LineSegments(unitEdges, boxMaterials[layer].edges));
        group.add(new THREE.Mesh(unitBox, boxMaterials[layer].faces));
        placeBox(group, e);
        return group;
    }

    function addBoxes() {
        data.layers.forEach((layer, index) => {
            for (const e of layer.entities) {
                const group = boxOf(index, e);
                scene.add(group);
                entityObjects.push({ layer: index, entity: e, object: group, kind: 'box' });
            }
        });
    }

    function addCloud(gltf) {
        gltf.scene.traverse((object) => {
            if (!object.isPoints) return;
            const old = object.material;
            object.material = new THREE.PointsMaterial({
                size: data.point_size, sizeAttenuation: false,
                vertexColors: !!object.geometry.getAttribute('color'), color: old.color,
            });
            let holder = object;
            while (holder && holder.userData.class_id === undefined) holder = holder.parent;
            const id = holder ? holder.userData.class_id : undefined;
            const c = id === undefined ? null : classById.get(id);
            cloudObjects.push({ className: c ? c.name : null, object });
        });
        scene.add(gltf.scene);
    }

    /// Top of the ground patches in the GL frame (scene-render's grid height).
    function groundTopGl() {
        let top = null;
        for (const e of data.layers[0].entities) {
            const c = data.classes.find((k) => k.name === e.class);
            if (!c || !c.ground) continue;
            const h = Math.min(e.H, 0.1);
            const y = e.y + 0.5 * e.H - h;
            top = top === null ? y : Math.min(top, y);
        }
        return -(top === null ? 1.65 : top);
    }

    function bevFit(aspect) {
        return util.bevFit(data, aspect);
    }

    function addGrid() {
        const fit = bevFit(1);
        const size = 2 * Math.ceil(Math.max(fit.halfWidth, fit.halfDepth) + 10);
        grid = new THREE.GridHelper(size, size, 0x8a93a0, 0xb4bcc8);
        grid.position.set(Math.round(fit.centre[0]), groundTopGl() + 0.01, -Math.round(fit.centre[1]));
        scene.add(grid);
    }

    // --- views ---
    function canvasSize() {
        return { w: canvas.clientWidth || 1, h: canvas.clientHeight || 1 };
    }

    /// The frame's camera, letterboxed into the canvas: the projection of views.cpp's
    /// projection_from_intrinsics with the intrinsics scaled and shifted to the image's rectangle.
    function cameraProjection() {
        const k = data.views.camera;
        const { w, h } = canvasSize();
        const s = Math.min(w / k.width, h / k.height);
        const ox = 0.5 * (w - k.width * s);
        const oy = 0.5 * (h - k.height * s);
        const fx = k.fx * s, fy = k.fy * s, cx = k.cx * s + ox, cy = k.cy * s + oy;
        const n = k.near, f = k.far;
        perspective.projectionMatrix.set(
            2 * fx / w, 0, 1 - 2 * cx / w, 0,
            0, 2 * fy / h, 2 * cy / h - 1, 0,
            0, 0, -(f + n) / (f - n), -2 * f * n / (f - n),
            0, 0, -1, 0);
        perspective.projectionMatrixInverse.copy(perspective.projectionMatrix).invert();
        Object.assign(backgroundImg.style, {
            left: ox + 'px', top: oy + 'px', width: k.width * s + 'px', height: k.height * s + 'px',
        });
    }

    function makeControls() {
        if (controls) controls.dispose();
        controls = new THREE.OrbitControls(camera, canvas);
        controls.addEventListener('change', () => {
            dirty = true;
            lastMotion = performance.now();
        });
        controls.addEventListener('start', () => {
            if (api.view === 'camera') {
                api.view = 'free';
                applyVisibility();
                updateProjection();
                markViewButtons();
            }
        });
    }

    function updateProjection() {
        const { w, h } = canvasSize();
        if (camera === orthographic) {
            const fit = bevFit(w / h);
            orthographic.left = -fit.halfHeight * w / h;
            orthographic.right = fit.halfHeight * w / h;
            orthographic.top = fit.halfHeight;
            orthographic.bottom = -fit.halfHeight;
            orthographic.updateProjectionMatrix();
        } else if (api.view === 'camera') {
            cameraProjection();
        } else {
            perspective.aspect = w / h;
            perspective.updateProjectionMatrix();
        }
        dirty = true;
    }

    function setView(name) {
        const k = data.views.camera;
        api.view = name;
        if (name === 'bev') {
            camera = orthographic;
            const fit = bevFit(1);
            const target = new THREE.Vector3(fit.centre[0], 0, -fit.centre[1]);
            orthographic.position.set(target.x, data.views.bev.height_m, target.z);
            orthographic.up.set(0, 0, -1);
            orthographic.zoom = 1;
            makeControls();
            controls.enableRotate = false;
            controls.screenSpacePanning = true;
            controls.target.copy(target);
        } else {
            camera = perspective;
            perspective.up.set(0, 1, 0);
            makeControls();
            if (name === 'chase') {
                perspective.fov = data.views.chase.fov;
                perspective.position.fromArray(data.views.chase.eye);
                controls.target.fromArray(data.views.chase.target);
            } else {
                perspective.fov = 2 * Math.atan(0.5 * k.height / k.fy) * 180 / Math.PI;
                perspective.position.set(0, 0, 0);
                controls.target.set(0, 0, -20);
            }
        }
        controls.update();
        updateProjection();
        applyVisibility();
        markViewButtons();
    }

    // --- visibility ---
    function visible(object) {
        for (let o = object; o; o = o.parent) if (!o.visible) return false;
        return true;
    }

    function applyVisibility() {
        const comparing = data.layers.length > 1;
        for (const item of entityObjects) {
            const on = !hiddenClasses.has(item.entity.class) && !hiddenLayers.has(item.layer);
            const wanted = item.kind === 'model' ? show.models : (show.boxes || (comparing && item.layer > 0));
            item.object.visible = on && wanted;
        }
        if (models) models.sync();
        for (const o of egoObjects) o.visible = show.ego && api.view !== 'camera';
        for (const c of cloudObjects) c.object.visible = show.cloud && !hiddenClasses.has(c.className);
        if (grid) grid.visible = show.grid && api.view === 'bev';
        const withImage = hasImage && show.background && api.view === 'camera';
        backgroundImg.hidden = !withImage;
        canvas.style.opacity = withImage ? '0.6' : '1';
        renderer.setClearColor(new THREE.Color(data.background_colour), withImage ? 0 : 1);
        dirty = true;
    }

    // --- picking and the details pane ---
    const raycaster = new THREE.Raycaster();

    function entityAt(clientX, clientY) {
        const rect = canvas.getBoundingClientRect();
        const ndc = new THREE.Vector2(((clientX - rect.left) / rect.width) * 2 - 1,
                                      -((clientY - rect.top) / rect.height) * 2 + 1);
        raycaster.setFromCamera(ndc, camera);
        const targets = entityObjects.filter((i) => visible(i.object)).map((i) => i.object);
        if (models) targets.push(...models.meshes.filter((m) => m.visible));
        for (const hit of raycaster.intersectObjects(targets, true)) {
            if (hit.object.isInstancedMesh) {
                const item = models.itemOf(hit);
                if (item) return item;
                continue;
            }
            if (!hit.object.isMesh || !visible(hit.object)) continue;
            for (let o = hit.object; o; o = o.parent) {
                const item = entityObjects.find((i) => i.object === o);
                if (item) return item;
            }
        }
        return null;
    }

    function showDetails(item) {
        if (highlight) {
            scene.remove(highlight);
            highlight = null;
        }
        if (!item) {
            detailsBox.hidden = true;
            dirty = true;
            return;
        }
        const e = item.entity;
        const rows = util.detailRows(e);
        if (data.layers.length > 1) rows.unshift(['file', data.layers[item.layer].label]);
        const table = document.createElement('table');
        for (const [k, v] of rows) {
            const tr = table.insertRow();
            const th = document.createElement('th');
            th.textContent = k;
            tr.appendChild(th);
            tr.insertCell().textContent = v;
        }
        detailsBox.replaceChildren(table);
        if (pinned === item) {
            const note = document.createElement('div');
            note.className = 'pinned';
            note.textContent = 'kept (click elsewhere to release)';
            detailsBox.appendChild(note);
        }
        detailsBox.hidden = false;
        detailsBox.dataset.entityId = e.id;
        highlight = new THREE.LineSegments(unitEdges, new THREE.LineBasicMaterial({ color: 0xffd400 }));
        placeBox(highlight, e);
        highlight.scale.multiplyScalar(1.02);
        scene.add(highlight);
        dirty = true;
    }

    canvas.addEventListener('pointermove', (event) => {
        if (pinned || event.buttons) return;
        showDetails(entityAt(event.clientX, event.clientY));
    });
    canvas.addEventListener('click', (event) => {
        const item = entityAt(event.clientX, event.clientY);
        pinned = item;
        showDetails(item);
    });
    canvas.addEventListener('pointerleave', () => { if (!pinned) showDetails(null); });

    function markViewButtons() {
        window.SceneViewerPanel.markView(api.view);
    }

    function buildPanel() {
        window.SceneViewerPanel.build({
            data, show, hiddenClasses, hiddenLayers, hasEgo: egoObjects.length > 0, hasImage,
            drive, setView, changed: applyVisibility,
        });
    }

    // --- level of detail: a uniform sample of the cloud while the view moves ---
    /// Draws each class's first share of points (the export shuffled them) or all of them.
    let cloudShare = 1;  // pace.points when the sample was drawn
    function setCloudDetail(sample) {
        const total = data.cloud ? data.cloud.points : 0;
        cloudShare = pace.points;
        const budget = Math.ceil(data.moving_points * cloudShare);
        coarse = sample && budget > 0 && total > budget;
        for (const c of cloudObjects) {
            const count = c.object.geometry.getAttribute('position').count;
            c.object.geometry.setDrawRange(0, coarse ? Math.ceil(count * budget / total) : Infinity);
        }
        dirty = true;
    }

    // --- frame loop ---
    function resize() {
        const { w, h } = canvasSize();
        renderer.setSize(w, h, false);
        updateProjection();
    }

    // --- level of detail: fewer pixels while the view moves, when moving frames come slowly ---
    const fullRatio = window.devicePixelRatio || 1;
    const pace = util.movingPace();

    function frame(now) {
        if (controls && controls.update()) {
            dirty = true;
            lastMotion = now;
        }
        const moving = now - lastMotion < 300;
        if (data.cloud && (moving !== coarse || (moving && pace.points !== cloudShare))) {
            setCloudDetail(moving);
        }
        const ratio = fullRatio * (moving ? pace.pixels : 1);
        if (ratio !== renderer.getPixelRatio()) {
            renderer.setPixelRatio(ratio);
            resize();
        }
        if (dirty) {
            renderer.render(scene, camera);
            dirty = false;
            ++api.frames;
            pace.drawn(moving, now);
            if (!coarse && ratio === fullRatio && api.fullFrameMs === null) {
                api.fullFrameMs = performance.now();
            }
        }
        requestAnimationFrame(frame);
    }

    /// Projects a KITTI camera-frame point to canvas pixels (CSS) in the current view.
    api.project = function (x, y, z) {
        const v = new THREE.Vector3(x, -y, -z).project(camera);
        const { w, h } = canvasSize();
        return { x: (v.x + 1) * 0.5 * w, y: (1 - v.y) * 0.5 * h };
    };
    api.setView = setView;
    api.orbitBenchmark = (ms) => util.orbitBenchmark(controls, ms);
    /// The shares of the full pixel ratio and of the cloud's moving sample drawn while the view
    /// moves (level of detail).
    api.movingDetail = () => ({ pixels: pace.pixels, points: pace.points });

    /// A drive: the class models as templates, then its first frame (frames load lazily).
    async function startDrive() {
        drive = window.SceneViewerDrive.create({
            scene, data, gltf: await parseGlb(data.drive.models_file), placeBox, toLambert,
            paintFirst, entityObjects, egoObjects, setModels,
            makeBox: (e) => boxOf(0, e),
            setImage: (src) => { backgroundImg.src = src; },
            markDirty: () => { dirty = true; },
            onFrameShown: () => {
                // The kept entity follows its track (or id) into the new frame.
                const key = pinned && (pinned.entity.track_id ?? pinned.entity.id);
                pinned = key === null ? null : entityObjects.find((i) => i.kind === 'model' &&
                    (i.entity.track_id ?? i.entity.id) === key) || null;
                showDetails(pinned);
                applyVisibility();
            },
        });
        api.drive = drive;
        await drive.show(0);
    }

    async function start() {
        if (!data) throw new Error('data/scene-data.js did not load');
        if (!window.THREE || !THREE.GLTFLoader) throw new Error('three.min.js did not load');
        renderer.setClearColor(new THREE.Color(data.background_colour), 1);
        if (data.background_image) backgroundImg.src = data.background_image;
        addLights();
        if (data.drive) {
            await startDrive();
        } else {
            addSceneModels(await parseGlb(data.scene_file));
            addBoxes();
        }
        mark('scene');
        addGrid();
        buildPanel();
        window.addEventListener('resize', resize);
        resize();
        setView(params.get('view') || 'camera');
        renderer.render(scene, camera);
        mark('rendered');
        // The first frame shows the entities; the cloud follows, first as a sample, then all of
        // it once nothing moves.
        await new Promise((resolve) => requestAnimationFrame(resolve));
        api.firstFrameMs = performance.now();
        if (data.cloud) {
            setStatus('loading the point cloud…');
            await cloudScriptLoaded();
            addCloud(await parseGlb(data.cloud.file));
            setCloudDetail(true);
            lastMotion = performance.now();
            applyVisibility();
            renderer.render(scene, camera);
            await new Promise((resolve) => requestAnimationFrame(resolve));
            api.cloudFrameMs = performance.now();
        } else {
            api.fullFrameMs = api.firstFrameMs;
        }
        setStatus('');
        resolveReady();
        requestAnimationFrame(frame);
    }

    start().catch((error) => {
        console.error('scene viewer:', error);
        setStatus('cannot show the scene: ' + error.message, true);
        rejectReady(error);
    });
})();
