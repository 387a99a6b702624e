// Benchmark of the browser viewer (not a test): a 50-car street with a 400k-point cloud written
// by `scene-render html`, opened from disk in Debian's headless chromium (software WebGL).
// Prints the time to first frame (navigation start -> the first frame after every file was
// decoded) over several page loads and the orbit frame rate measured with requestAnimationFrame.
// Then a drive of --drive-frames frames of the same street with the cars moving (tracked): the
// time to write the folder, to the first frame, to jump to the middle frame, and the frames
// shown per second while playing at the drive's 10 Hz.
// usage: node scripts/bench-viewer.mjs [BUILD_DIR] [OUT_DIR] [--points N] [--entities N]
//        [--loads N] [--orbit-ms MS] [--size WxH] [--drive-frames N]
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { launch, loadModules, openViewer } from '../tests/scene_viewer/web/browser.mjs';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const positional = [];
const opts = { points: 400000, entities: 50, loads: 5, 'orbit-ms': 5000, size: '1280x720',
               'drive-frames': 1000 };
const argv = process.argv.slice(2);
for (let i = 0; i < argv.length; ++i) {
    if (argv[i].startsWith('--')) opts[argv[i].slice(2)] = argv[++i];
    else positional.push(argv[i]);
}
const build = path.resolve(positional[0] || path.join(root, 'build'));
const out = path.resolve(positional[1] || path.join(root, 'out/bench-viewer'));
const [width, height] = String(opts.size).split('x').map(Number);
fs.mkdirSync(out, { recursive: true });

/// A street of `n` cars in four lanes, road and sidewalks, KITTI's camera.
function street(n) {
    const entities = [
        { id: 'road-1', class: 'road', class_id: 7, x: 0, y: 1.625, z: 60, theta: -Math.PI / 2,
          W: 14, H: 0.05, L: 120, confidence: 1, point_count: 0 },
    ];
    for (let i = 0; i < n; ++i) {
        const lane = i % 4, row = Math.floor(i / 4);
        entities.push({ id: 'car-' + (i + 1), class: 'car', class_id: 26, x: -5.25 + 3.5 * lane,
                        y: 0.9, z: 8 + 7.5 * row, theta: lane < 2 ? Math.PI / 2 : -Math.PI / 2,
                        W: 1.8, H: 1.5, L: 4.2, confidence: 0.9, point_count: 0 });
    }
    return {
        schema_version: '1.0.0',
        frame: { id: 'bench', convention: 'kitti_camera',
                 camera: { width: 1242, height: 375, fx: 721.5377, fy: 721.5377, cx: 609.5593,
                           cy: 172.854, baseline_m: 0.5372 } },
        entities,
    };
}

/// A binary PLY of `count` points: the road surface and the cars' boxes, coloured by class.
function cloud(doc, count, file) {
    const header = 'ply\nformat binary_little_endian 1.0\nelement vertex ' + count +
        '\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n' +
        'property uchar green\nproperty uchar blue\nproperty int scalar_class\nend_header\n';
    const record = 19;
    const body = Buffer.alloc(count * record);
    let seed = 1;
    const random = () => ((seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648);
    const cars = doc.entities.filter((e) => e.class === 'car');
    for (let i = 0; i < count; ++i) {
        let x, y, z, rgb, cls;
        if (i % 2 === 0) {
            x = -7 + 14 * random(); y = 1.6; z = 3 + 110 * random(); rgb = [128, 64, 128]; cls = 7;
        } else {
            const c = cars[i % cars.length];
            x = c.x + (random() - 0.5) * c.W; y = c.y + (random() - 0.5) * c.H;
            z = c.z - 0.5 * c.L * random(); rgb = [0, 0, 142]; cls = 26;
        }
        const at = i * record;
        body.writeFloatLE(x, at); body.writeFloatLE(y, at + 4); body.writeFloatLE(z, at + 8);
        body.writeUInt8(rgb[0], at + 12); body.writeUInt8(rgb[1], at + 13);
        body.writeUInt8(rgb[2], at + 14); body.writeInt32LE(cls, at + 15);
    }
    fs.writeFileSync(file, Buffer.concat([Buffer.from(header, 'latin1'), body]));
}

/// The street as a drive: every car keeps its track and drives along its lane (the two lanes
/// on each side in opposite directions), 10 frames a second.
function writeDrive(dir, frames) {
    fs.mkdirSync(dir, { recursive: true });
    const base = street(Number(opts.entities));
    const index = { schema_version: '1.1.0', id: 'bench-drive', fps: 10, frames: [] };
    for (let f = 0; f < frames; ++f) {
        const t = f / 10;
        const doc = JSON.parse(JSON.stringify(base));
        doc.schema_version = '1.1.0';
        doc.frame.id = String(f).padStart(6, '0');
        doc.frame.timestamp = t;
        doc.entities.forEach((e, i) => {
            if (e.class !== 'car') return;
            const v = e.x < 0 ? 8 : -8;
            e.z = 8 + ((e.z - 8 + v * t) % 90 + 90) % 90;
            e.track_id = i;
            e.velocity = { vx: 0, vz: v };
        });
        const file = doc.frame.id + '.json';
        fs.writeFileSync(path.join(dir, file), JSON.stringify(doc));
        index.frames.push({ index: f, file, timestamp: t });
    }
    fs.writeFileSync(path.join(dir, 'sequence.json'), JSON.stringify(index));
}

async function benchDrive() {
    const frames = Number(opts['drive-frames']);
    const driveDir = path.join(out, 'drive');
    writeDrive(driveDir, frames);
    const viewer = path.join(out, 'drive-viewer');
    const t0 = Date.now();
    const w = spawnSync(path.join(build, 'scene_viewer/scene-render'),
                        ['html', driveDir, '--out', viewer], { encoding: 'utf8' });
    if (w.status !== 0) {
        console.error(w.stderr);
        process.exit(1);
    }
    const write = Date.now() - t0;
    const ctx = await launch(playwright, '/usr/bin/chromium');
    const { page, report } = await openViewer(ctx, viewer, '?view=chase', { width, height });
    const first = await page.evaluate(() => window.viewer.firstFrameMs);
    const jump = await page.evaluate(async (n) => {
        const t = performance.now();
        await window.viewer.drive.show(Math.floor(n / 2));
        await new Promise((r) => requestAnimationFrame(() => r()));
        return performance.now() - t;
    }, frames);
    const play = await page.evaluate(() => new Promise((resolve) => {
        const drive = window.viewer.drive;
        let shown = 0;
        drive.onChange.push(() => ++shown);
        const t = performance.now();
        drive.play();
        setTimeout(() => {
            drive.pause();
            resolve({ shown, ms: performance.now() - t, requested: drive.requested.size });
        }, 3000);
    }));
    if (report.errors.length || report.outside.length) {
        console.error('page errors or outside requests:', report);
        process.exit(1);
    }
    await ctx.close();
    console.log(`drive: ${frames} frames of ${Number(opts.entities)} cars; folder written in ${write} ms; ` +
                `first frame ${first.toFixed(0)} ms from navigation; jump to frame ${Math.floor(frames / 2)} ` +
                `${jump.toFixed(0)} ms; playing: ${(1000 * play.shown / play.ms).toFixed(1)} frames shown ` +
                `per second (drive 10 Hz); ${play.requested} of ${frames} frame scripts loaded`);
}

const doc = street(Number(opts.entities));
const scenePath = path.join(out, 'street.json');
const cloudPath = path.join(out, 'cloud.ply');
fs.writeFileSync(scenePath, JSON.stringify(doc));
cloud(doc, Number(opts.points), cloudPath);
const viewerDir = path.join(out, 'viewer');
const started = Date.now();
const r = spawnSync(path.join(build, 'scene_viewer/scene-render'),
                    ['html', scenePath, '--cloud', cloudPath, '--out', viewerDir,
                     '--moving-points', String(opts['moving-points'] || 30000)], { encoding: 'utf8' });
if (r.status !== 0) {
    console.error(r.stderr);
    process.exit(1);
}
const writeMs = Date.now() - started;
const folderBytes = fs.readdirSync(viewerDir, { recursive: true })
    .map((f) => fs.statSync(path.join(viewerDir, f))).filter((s) => s.isFile())
    .reduce((sum, s) => sum + s.size, 0);

const { playwright } = loadModules(path.join(root, 'scripts/npm/node_modules'));
const context = await launch(playwright, '/usr/bin/chromium');
const firstFrames = [];
const fullFrames = [];
const cloudFrames = [];
let orbit = null;
for (let i = 0; i < Number(opts.loads); ++i) {
    const { page, report } = await openViewer(context, viewerDir, '?view=chase', { width, height });
    if (report.errors.length || report.outside.length) {
        console.error('page errors or outside requests:', report);
        process.exit(1);
    }
    firstFrames.push(await page.evaluate(() => window.viewer.firstFrameMs));
    await page.waitForFunction(() => window.viewer.fullFrameMs !== null, null, { timeout: 60000 });
    fullFrames.push(await page.evaluate(() => window.viewer.fullFrameMs));
    cloudFrames.push(await page.evaluate(() => window.viewer.cloudFrameMs));
    if (i === Number(opts.loads) - 1) {
        // The first orbit lowers the moving detail until frames come at 30 fps; the second
        // runs at the detail reached.
        orbit = [];
        for (let k = 0; k < 2; ++k) {
            orbit.push(await page.evaluate((ms) => window.viewer.orbitBenchmark(ms),
                                           Number(opts['orbit-ms'])));
            orbit[k].detail = await page.evaluate(() => window.viewer.movingDetail());
        }
    }
    await page.close();
}
await context.close();
const summary = (values) => {
    const s = [...values].sort((a, b) => a - b);
    return `median ${s[Math.floor(s.length / 2)].toFixed(0)}, min ${s[0].toFixed(0)}, ` +
        `max ${s[s.length - 1].toFixed(0)}`;
};
const gl = 'SwiftShader (software WebGL)';
console.log(`scene: ${doc.entities.length - 1} cars + road, ${Number(opts.points).toLocaleString('en')} points;` +
            ` folder ${(folderBytes / 1048576).toFixed(1)} MiB written in ${writeMs} ms by scene-render html`);
console.log(`browser: Debian chromium headless, ${gl}, ${width}x${height}; load average ` +
            os.loadavg().map((v) => v.toFixed(2)).join(' ') + ` on ${os.cpus().length} cores`);
console.log(`ms from navigation (${firstFrames.length} loads): first frame (entities) ` +
            summary(firstFrames));
console.log(`  first frame with the cloud (${opts['moving-points'] || 30000}-point sample) ` +
            summary(cloudFrames));
console.log(`  first frame with every point ${summary(fullFrames)}`);
orbit.forEach((o, k) => {
    console.log(`orbit ${k + 1} (chase view, auto-rotate, ${opts['orbit-ms']} ms): ${o.fps.toFixed(1)} fps ` +
                `over ${o.frames} frames, worst frame ${o.worst_ms.toFixed(1)} ms; moving detail ` +
                `reached: ${o.detail.pixels} of the pixel ratio, ${o.detail.points} of the ` +
                `${opts['moving-points'] || 30000}-point sample`);
});
await benchDrive();
