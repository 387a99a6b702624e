// The drive timeline of the scene viewer page (docs/viewer.md): frames loaded lazily from one
// classic script each (frames/NNNNNN.js calls SceneViewerFrames.add), the class models placed
// for every entity of the frame shown, track trails, a slider and play/pause at the drive's
// frame rate. A classic script: it sets window.SceneViewerDrive before viewer.js runs.
(function () {
    'use strict';

    /// Frame scripts report here; each load waits for its frame's position.
    const waiting = new Map();  // position -> {resolve, reject}
    window.SceneViewerFrames = {
        add(payload) {
            const w = waiting.get(payload.position);
            if (!w) return;
            waiting.delete(payload.position);
            w.resolve(payload);
        },
    };

    /// The drive controller. `ctx`: scene, data, gltf (models.glb parsed), placeBox(object,
    /// entity), makeBox(entity), toLambert(material), paintFirst(object), entityObjects,
    /// egoObjects, setModels([{entity, root}]) (draws them as instances and adds their items to
    /// entityObjects), setImage(src), markDirty(), onFrameShown(position).
    function create(ctx) {
        const drive = ctx.data.drive;
        const frames = drive.frames;
        const cache = new Map();      // position -> Promise of the frame's payload
        const requested = new Set();  // frame scripts asked for (the page's lazy loading)
        let shown = -1;               // position on screen
        let target = 0;               // position asked for last
        let shownObjects = [];
        let playing = false;
        let clock = null;             // {wall, time}: playback started at drive time `time`
        const onChange = [];

        // --- class models: templates fitted to the unit box, placed like scene-render ---
        const templates = new Map();
        ctx.gltf.scene.traverse((object) => {
            if (!object.isMesh) return;
            const materials = Array.isArray(object.material) ? object.material : [object.material];
            const lambert = materials.map(ctx.toLambert);
            object.material = Array.isArray(object.material) ? lambert : lambert[0];
        });
        for (const object of [...ctx.gltf.scene.children]) {
            const name = object.userData.name !== undefined ? object.userData.name : object.name;
            if (name.startsWith('class:')) {
                templates.set(name.slice(6), object);
            } else if (name === 'ego') {
                ctx.scene.add(object);
                ctx.egoObjects.push(object);
            }
        }
        const classByName = new Map(ctx.data.classes.map((c) => [c.name, c]));
        const patchMaterials = new Map();  // class -> material, shared by patches and boxes
        const unitBox = new THREE.BoxGeometry(1, 1, 1);

        function classMaterial(name) {
            let material = patchMaterials.get(name);
            if (!material) {
                const c = classByName.get(name);
                material = new THREE.MeshLambertMaterial({ color: c ? c.colour : '#808080' });
                patchMaterials.set(name, material);
            }
            return material;
        }

        /// A ground patch: the class colour on the box's bottom face, 0.1 m thick at most.
        function groundPatch(e) {
            const mesh = new THREE.Mesh(unitBox, classMaterial(e.class));
            const h = Math.min(e.H, 0.1);
            ctx.placeBox(mesh, Object.assign({}, e, { y: e.y + 0.5 * e.H - 0.5 * h, H: h }));
            ctx.paintFirst(mesh);
            return mesh;
        }

        /// The class model (or a box in the class colour) placed for `e`, outside the scene.
        function modelOf(e) {
            const template = templates.get(e.class);
            const group = new THREE.Group();
            if (template) {
                group.add(template.clone());
            } else {
                group.add(new THREE.Mesh(unitBox, classMaterial(e.class)));
            }
            ctx.placeBox(group, e);
            return group;
        }

        // --- trails: each track's ground contact points, drawn for the last trail_frames. In a
        // drive with poses (drive.world) the points lie in the drive's world and the group
        // holding them is moved into the camera of the frame shown, so trails stay on the ground
        // as the car drives; the car's own path is a track of its own. ---
        const trailGroup = new THREE.Group();
        trailGroup.matrixAutoUpdate = false;
        ctx.scene.add(trailGroup);
        const flip = new THREE.Matrix4().makeScale(1, -1, -1);  // KITTI axes <-> the page's
        const trails = drive.tracks.map((track) => {
            const positions = new Float32Array(track.points.length * 3);
            track.points.forEach(([, x, yBottom, z], i) => {
                positions.set([x, -yBottom + 0.05, -z], 3 * i);
            });
            const geometry = new THREE.BufferGeometry();
            geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
            const c = classByName.get(track.class);
            const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({
                color: new THREE.Color(c ? c.colour : '#ffd400').multiplyScalar(0.7),
            }));
            line.frustumCulled = false;
            line.visible = false;
            trailGroup.add(line);
            return { frames: track.points.map((p) => p[0]), line };
        });
        let trailsOn = drive.trail_frames > 0;

        /// First index in the sorted array `a` whose value is >= v.
        function lowerBound(a, v) {
            let lo = 0, hi = a.length;
            while (lo < hi) {
                const mid = (lo + hi) >> 1;
                if (a[mid] < v) lo = mid + 1; else hi = mid;
            }
            return lo;
        }

        function updateTrails(position) {
            if (drive.world) {
                const cameraFromWorld = new THREE.Matrix4().fromArray(
                    frames[position].camera_from_world);
                trailGroup.matrix.copy(flip).multiply(cameraFromWorld).multiply(flip);
                trailGroup.matrixWorldNeedsUpdate = true;
            }
            for (const t of trails) {
                const begin = lowerBound(t.frames, position - drive.trail_frames + 1);
                const end = lowerBound(t.frames, position + 1);
                t.line.geometry.setDrawRange(begin, end - begin);
                t.line.visible = trailsOn && end - begin >= 2 && t.frames[end - 1] === position;
            }
        }

        // --- lazy loading ---
        function load(position) {
            if (cache.has(position)) return cache.get(position);
            const promise = new Promise((resolve, reject) => {
                waiting.set(position, { resolve, reject });
                const tag = document.createElement('script');
                tag.src = frames[position].script;
                tag.addEventListener('error', () => {
                    waiting.delete(position);
                    cache.delete(position);
                    reject(new Error('cannot load ' + frames[position].script));
                });
                requested.add(frames[position].script);
                document.head.appendChild(tag);
            });
            cache.set(position, promise);
            return promise;
        }

        function prefetch(position) {
            for (let p = position + 1; p <= Math.min(position + 3, frames.length - 1); ++p) {
                load(p).catch(() => {});
                if (frames[p].image) new Image().src = frames[p].image;
            }
        }

        function display(position, payload) {
            for (const o of shownObjects) ctx.scene.remove(o);
            shownObjects = [];
            ctx.entityObjects.length = 0;
            const placed = [];
            for (const e of payload.entities) {
                const c = classByName.get(e.class);
                const box = ctx.makeBox(e);
                ctx.scene.add(box);
                shownObjects.push(box);
                ctx.entityObjects.push({ layer: 0, entity: e, object: box, kind: 'box' });
                if (c && c.ground) {
                    const patch = groundPatch(e);
                    ctx.scene.add(patch);
                    shownObjects.push(patch);
                    ctx.entityObjects.push({ layer: 0, entity: e, object: patch, kind: 'model' });
                } else {
                    placed.push({ entity: e, root: modelOf(e) });
                }
            }
            ctx.setModels(placed);
            shown = position;
            updateTrails(position);
            if (frames[position].image) ctx.setImage(frames[position].image);
            ui.slider.value = String(position);
            const f = frames[position];
            ui.label.textContent = 'frame ' + f.index + ' · ' + f.time.toFixed(2) + ' s · ' +
                payload.entities.length + ' entities';
            ctx.onFrameShown(position);
            ctx.markDirty();
            for (const fn of onChange) fn(position);
        }

        /// Shows the frame at `position` (0-based in the index); resolves once it is drawn.
        async function show(position) {
            position = Math.max(0, Math.min(frames.length - 1, Math.round(position)));
            target = position;
            const payload = await load(position);
            if (target !== position) return;  // a later request won
            display(position, payload);
            prefetch(position);
        }

        // --- playback at the drive's clock (timestamps, else index / fps) ---
        function tick(now) {
            if (!playing) return;
            const time = clock.time + (now - clock.wall) / 1000;
            let next = shown;
            while (next + 1 < frames.length && frames[next + 1].time <= time) ++next;
            if (next !== shown && next !== target) show(next).catch(fail);
            if (next === frames.length - 1 && shown === next) {
                pause();
                return;
            }
            requestAnimationFrame(tick);
        }

        function play() {
            if (playing) return;
            if (shown >= frames.length - 1) show(0).catch(fail);
            playing = true;
            clock = { wall: performance.now(), time: frames[Math.max(0, target)].time };
            ui.play.textContent = '❚❚';
            ui.play.title = 'pause';
            requestAnimationFrame(tick);
        }

        function pause() {
            playing = false;
            ui.play.textContent = '▶';
            ui.play.title = 'play';
        }

        function fail(error) {
            pause();
            console.error('scene viewer:', error);
            ui.label.textContent = error.message;
        }

        // --- the timeline ---
        const ui = {};
        (function buildTimeline() {
            const bar = document.createElement('div');
            bar.id = 'timeline';
            ui.play = document.createElement('button');
            ui.play.addEventListener('click', () => (playing ? pause() : play()));
            ui.slider = document.createElement('input');
            ui.slider.type = 'range';
            ui.slider.min = '0';
            ui.slider.max = String(frames.length - 1);
            ui.slider.value = '0';
            ui.slider.addEventListener('input', () => {
                pause();
                show(Number(ui.slider.value)).catch(fail);
            });
            ui.label = document.createElement('span');
            bar.append(ui.play, ui.slider, ui.label);
            document.getElementById('stage').appendChild(bar);
            pause();
            window.addEventListener('keydown', (event) => {
                if (event.target instanceof HTMLInputElement && event.target.type !== 'range') return;
                if (event.key === ' ') {
                    event.preventDefault();
                    if (playing) pause(); else play();
                } else if (event.key === 'ArrowRight' || event.key === 'ArrowLeft') {
                    event.preventDefault();
                    pause();
                    show(target + (event.key === 'ArrowRight' ? 1 : -1)).catch(fail);
                }
            });
        })();

        return {
            count: frames.length,
            get position() { return shown; },
            get playing() { return playing; },
            requested,
            show,
            play,
            pause,
            onChange,
            /// Trails drawn in the frame shown.
            visibleTrails: () => trails.filter((t) => t.line.visible).length,
            /// The page coordinates of the last point of each trail drawn (the world moved into
            /// the camera of the frame shown).
            trailEnds() {
                trailGroup.updateMatrixWorld(true);
                return trails.filter((t) => t.line.visible).map((t) => {
                    const a = t.line.geometry.attributes.position;
                    const range = t.line.geometry.drawRange;
                    const k = range.start + range.count - 1;
                    const p = new THREE.Vector3(a.getX(k), a.getY(k), a.getZ(k));
                    return p.applyMatrix4(t.line.matrixWorld).toArray();
                });
            },
            setTrails(on) {
                trailsOn = on;
                if (shown >= 0) updateTrails(shown);
                ctx.markDirty();
            },
        };
    }

    window.SceneViewerDrive = { create };
})();
