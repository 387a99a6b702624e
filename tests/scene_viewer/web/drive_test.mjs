// Browser test of `scene-render html` on a drive (label browser): a synthetic drive rendered by
// `scene-render sensors --frames`, its per-frame truth shown as a drive in headless chromium.
//   - frames load lazily: after the page is ready only the first frame and the next few were
//     requested;
//   - the first and the last frame's camera views show scene-render's render of the same frame
//     file (the same silhouettes within a few pixels);
//   - a car kept by a click at its projected centre stays kept as the drive moves: the details
//     pane shows the entity of the same track in the last frame;
//   - play runs at the drive's clock (not faster, at most a few seconds slower) and stops at
//     the end; the trails of the tracks in the frame are drawn;
//   - with --backgrounds, each frame shows its own left image;
//   - a drive with a moving camera draws its trails in the drive's world: each ends where its
//     thing stands in the frame shown, the camera's path under the camera;
//   - no error logged, no request outside the folder (served by a static web server).
// usage: node drive_test.mjs SCENE_RENDER DRIVE_SCENE.json OUT_DIR NODE_MODULES CHROMIUM
// Exit 0 pass, 1 fail, 77 skipped (chromium or the npm packages missing).
import fs from 'node:fs';
import path from 'node:path';
import { fail, launch, loadModules, openViewer, readPng, runTool, serveFolder } from './browser.mjs';
import { checkReport, compareMasks, foreground } from './compare.mjs';

const [sceneRender, driveScene, outDir, nodeModules, chromium] = process.argv.slice(2);
const { playwright, PNG } = loadModules(nodeModules);
if (!fs.existsSync(chromium || '')) {
    console.log('SKIPPED: chromium not found (' + chromium + ')');
    process.exit(77);
}
const kFrames = 8;
const kFps = 10;

const run = (args) => runTool(sceneRender, args);

/// The truth drive without ground and buildings (objects against the background), as a
/// sequence of its own; returns its folder and the frame documents.
function objectsDrive(truthDir) {
    const stuff = new Set(['road', 'sidewalk', 'parking', 'terrain', 'building', 'wall', 'fence']);
    const dir = path.join(outDir, 'objects');
    fs.mkdirSync(dir, { recursive: true });
    const index = JSON.parse(fs.readFileSync(path.join(truthDir, 'sequence.json'), 'utf8'));
    const docs = index.frames.map((f) => {
        const doc = JSON.parse(fs.readFileSync(path.join(truthDir, f.file), 'utf8'));
        doc.entities = doc.entities.filter((e) => !stuff.has(e.class));
        fs.writeFileSync(path.join(dir, f.file), JSON.stringify(doc));
        return { file: path.join(dir, f.file), doc };
    });
    fs.writeFileSync(path.join(dir, 'sequence.json'), JSON.stringify(index));
    return { dir, frames: docs };
}

/// The page's camera view of frame `k` against scene-render's render of the frame's file.
async function compareFrame(page, frame, k) {
    await page.evaluate((p) => window.viewer.drive.show(p), k);
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    const shot = path.join(outDir, `frame${k}-viewer.png`);
    const reference = path.join(outDir, `frame${k}-reference.png`);
    await page.screenshot({ path: shot });
    run([frame.file, '--view', 'camera', '-o', reference]);
    const a = readPng(PNG, shot), b = readPng(PNG, reference);
    if (a.width !== b.width || a.height !== b.height) {
        fail(`screenshot ${a.width}x${a.height}, reference ${b.width}x${b.height}`);
    }
    compareMasks(foreground(a, 40), foreground(b, 40), a, `frame ${k} foreground`, shot, reference);
}

/// Keeps the nearest tracked car of the first frame by a click at its projected centre, then
/// shows the last frame: the pane must follow the track.
async function followTrack(page, frames, size) {
    await page.evaluate(() => window.viewer.drive.show(0));
    const cars = frames[0].doc.entities.filter((e) => e.class === 'car' && e.track_id !== undefined);
    const car = cars.sort((p, q) => p.z - q.z)[0];
    const at = await page.evaluate((e) => window.viewer.project(e.x, e.y, e.z), car);
    if (!(at.x > 0 && at.x < size.width && at.y > 0 && at.y < size.height)) {
        fail(`${car.id} projects outside the view (${at.x}, ${at.y})`);
    }
    await page.mouse.move(at.x, at.y);
    await page.mouse.click(at.x, at.y);
    const first = await page.locator('#details').getAttribute('data-entity-id');
    if (first !== car.id) fail(`a click on ${car.id} shows '${first}'`);
    const last = frames[frames.length - 1].doc.entities.find((e) => e.track_id === car.track_id);
    if (!last) fail(`track ${car.track_id} is not in the last frame`);
    await page.evaluate((p) => window.viewer.drive.show(p), frames.length - 1);
    const shown = await page.locator('#details').getAttribute('data-entity-id');
    const text = await page.locator('#details').innerText();
    console.log(`kept ${car.id} (track ${car.track_id}); last frame shows ${shown}`);
    if (shown !== last.id || !text.includes(last.x.toFixed(2))) {
        fail(`after the drive moved the pane shows '${shown}' (${text.replace(/\n/g, ' ')}), ` +
             `expected ${last.id} at x ${last.x.toFixed(2)}`);
    }
    await page.mouse.click(2, 2);  // release
}

/// Plays from the first frame and times the run to the last one.
async function playTiming(page) {
    await page.evaluate(() => window.viewer.drive.show(0));
    const result = await page.evaluate(() => new Promise((resolve) => {
        const drive = window.viewer.drive;
        const started = performance.now();
        drive.onChange.push((p) => {
            if (p === drive.count - 1) {
                requestAnimationFrame(() => resolve({ ms: performance.now() - started,
                                                      playing: drive.playing,
                                                      trails: drive.visibleTrails() }));
            }
        });
        drive.play();
    }));
    const expected = (kFrames - 1) * 1000 / kFps;
    console.log(`play: last frame after ${result.ms.toFixed(0)} ms (drive clock ${expected} ms), ` +
                `${result.trails} trails drawn`);
    if (result.ms < 0.9 * expected || result.ms > expected + 4000) {
        fail(`play took ${result.ms.toFixed(0)} ms for ${expected} ms of drive`);
    }
    if (result.playing) fail('play does not stop at the last frame');
    if (result.trails < 1) fail('no track trail is drawn at the last frame');
}

/// A drive with a moving camera (sensors --ego-speed: its truth carries poses): the trails lie in
/// the drive's world, so at the last frame each trail ends where its thing stands in that
/// frame, and the camera's own path ends on the ground under the camera.
async function worldTrails(context) {
    const moving = path.join(outDir, 'moving');
    run(['sensors', driveScene, '--out', moving, '--frames', String(kFrames), '--fps',
         String(kFps), '--size', '621x188', '--ego-speed', '6', '--ego-yaw-rate', '5']);
    const { dir, frames } = objectsDrive(path.join(moving, 'truth'));
    const viewerDir = path.join(outDir, 'viewer-moving');
    run(['html', dir, '--out', viewerDir]);
    const { page, report } = await openViewer(context, viewerDir, '?ui=0');
    const result = await page.evaluate(async (last) => {
        await window.viewer.drive.show(last);
        return { world: window.SCENE_VIEWER_DATA.drive.world, ends: window.viewer.drive.trailEnds() };
    }, frames.length - 1);
    if (result.world !== true) fail('a drive with poses is not drawn in its world');
    // Where the page draws a KITTI ground point (x, y_ground, z) of the frame shown.
    const page3 = (x, y, z) => [x, -y + 0.05, -z];
    const expected = [page3(0, 1.65, 0)];  // the camera's path: the ground under it
    for (const e of frames[frames.length - 1].doc.entities) {
        if (e.track_id !== undefined) expected.push(page3(e.x, e.y + 0.5 * e.H, e.z));
    }
    console.log(`moving drive: ${result.ends.length} trails drawn at the last frame`);
    if (result.ends.length < 2) fail('the moving drive draws no trail besides the camera path');
    for (const end of result.ends) {
        const off = Math.min(...expected.map((q) => Math.hypot(...q.map((v, k) => v - end[k]))));
        if (off > 0.1) fail(`a trail ends at ${end.map((v) => v.toFixed(2))}, ${off.toFixed(2)} m from any thing`);
    }
    checkReport(report);
}

async function driveTest() {
    const sensors = path.join(outDir, 'sensors');
    run(['sensors', driveScene, '--out', sensors, '--frames', String(kFrames), '--fps',
         String(kFps), '--size', '621x188']);
    const { dir, frames } = objectsDrive(path.join(sensors, 'truth'));
    const viewerDir = path.join(outDir, 'viewer');
    run(['html', dir, '--out', viewerDir]);
    const data = fs.readFileSync(path.join(viewerDir, 'data/scene-data.js'), 'utf8');
    const size = JSON.parse(data.slice(data.indexOf('{'), data.lastIndexOf('}') + 1)).views.camera;
    const context = await launch(playwright, chromium);
    const server = await serveFolder(viewerDir);
    try {
        const { page, report } = await openViewer(context, server.url, '?ui=0',
                                                  { width: size.width, height: size.height });
        const early = await page.evaluate(() => [...window.viewer.drive.requested]);
        console.log('requested at load: ' + early.join(' '));
        if (!early.includes('frames/000000.js') || early.length > 4) {
            fail('the page did not load the frames lazily: ' + early.join(' '));
        }
        await compareFrame(page, frames[0], 0);
        await compareFrame(page, frames[frames.length - 1], frames.length - 1);
        await followTrack(page, frames, size);
        await playTiming(page);
        checkReport(report);

        // Each frame's own left image behind the camera view.
        const withImages = path.join(outDir, 'viewer-images');
        run(['html', dir, '--backgrounds', path.join(sensors, 'image_2'), '--out', withImages]);
        const images = await openViewer(context, withImages, '');
        const src = await images.page.evaluate(async () => {
            await window.viewer.drive.show(3);
            const img = document.getElementById('background');
            await img.decode();
            return { src: img.getAttribute('src'), width: img.naturalWidth };
        });
        console.log(`frame 3 shows ${src.src} (${src.width} px wide)`);
        if (src.src !== 'frames/000003.png' || src.width !== 621) fail('frame 3 shows ' + JSON.stringify(src));
        checkReport(images.report);
        await worldTrails(context);
    } finally {
        server.close();
        await context.close();
    }
}

fs.mkdirSync(outDir, { recursive: true });
driveTest().then(() => console.log('PASS'), (e) => fail(e.stack || String(e)));
