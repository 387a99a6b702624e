// Browser tests of `scene-render html` (label browser): the page in Debian's headless chromium.
//   camera: the camera view's screenshot against scene-render's own render of the same file
//           (the same silhouettes within a few pixels, whatever the shading), no errors logged,
//           no request outside the folder; objects alone against the background, then the
//           whole street with the cars' blue bodies compared (what hides what).
//   pick:   a pointer at a car's projected centre shows that car's id in the details pane, the
//           folder served by a static web server on the loopback interface.
// usage: node viewer_test.mjs camera|pick SCENE_RENDER ENTITIES.json OUT_DIR NODE_MODULES CHROMIUM
// Exit 0 pass, 1 fail, 77 skipped (chromium or the npm packages missing).
import fs from 'node:fs';
import path from 'node:path';
import { fail, launch, loadModules, openViewer, readPng, runTool, serveFolder } from './browser.mjs';
import { carBlue, checkReport, compareMasks, foreground } from './compare.mjs';

const [mode, sceneRender, entitiesFile, outDir, nodeModules, chromium] = process.argv.slice(2);
const { playwright, PNG } = loadModules(nodeModules);
if (!fs.existsSync(chromium || '')) {
    console.log('SKIPPED: chromium not found (' + chromium + ')');
    process.exit(77);
}

const run = (args) => runTool(sceneRender, args);

/// The test scene without ground and buildings: objects against the background, so the
/// silhouettes compare every box's place.
function objectsOnly(file) {
    const doc = JSON.parse(fs.readFileSync(file, 'utf8'));
    const stuff = new Set(['road', 'sidewalk', 'parking', 'terrain', 'building', 'wall', 'fence']);
    doc.entities = doc.entities.filter((e) => !stuff.has(e.class));
    const out = path.join(outDir, 'objects.json');
    fs.writeFileSync(out, JSON.stringify(doc));
    return { out, doc };
}

/// Renders `file` in the camera view with scene-render and in the viewer; returns both images.
async function cameraPair(context, file, name, k) {
    const viewerDir = path.join(outDir, name);
    run(['html', file, '--out', viewerDir]);
    const reference = path.join(outDir, name + '-reference.png');
    run([file, '--view', 'camera', '-o', reference]);
    const { page, report } = await openViewer(context, viewerDir, '?ui=0',
                                              { width: k.width, height: k.height });
    const shot = path.join(outDir, name + '-viewer.png');
    await page.screenshot({ path: shot });
    checkReport(report);
    const a = readPng(PNG, shot), b = readPng(PNG, reference);
    if (a.width !== b.width || a.height !== b.height) {
        fail(`screenshot ${a.width}x${a.height}, reference ${b.width}x${b.height}`);
    }
    return { a, b, shot, reference };
}

async function cameraTest() {
    const { out: objects, doc } = objectsOnly(entitiesFile);
    const k = doc.frame.camera;
    const context = await launch(playwright, chromium);
    try {
        const { a, b, shot, reference } = await cameraPair(context, objects, 'objects', k);
        compareMasks(foreground(a, 40), foreground(b, 40), a, 'foreground', shot, reference);
        const street = await cameraPair(context, entitiesFile, 'street', k);
        compareMasks(carBlue(street.a), carBlue(street.b), street.a, 'car-blue', street.shot,
                     street.reference);
    } finally {
        await context.close();
    }
}

async function pickTest() {
    const doc = JSON.parse(fs.readFileSync(entitiesFile, 'utf8'));
    const k = doc.frame.camera;
    // The nearest car: nothing stands in front of it.
    const car = doc.entities.filter((e) => e.class === 'car').sort((p, q) => p.z - q.z)[0];
    const viewerDir = path.join(outDir, 'viewer');
    run(['html', entitiesFile, '--out', viewerDir]);
    const context = await launch(playwright, chromium);
    const server = await serveFolder(viewerDir);
    try {
        const { page, report } = await openViewer(context, server.url, '',
                                                  { width: k.width, height: k.height });
        // The pinhole projection of the box centre, computed here from the file (not the page).
        const u = k.fx * car.x / car.z + k.cx, v = k.fy * car.y / car.z + k.cy;
        await page.mouse.move(u, v);
        await page.mouse.click(u, v);
        const shown = await page.locator('#details').getAttribute('data-entity-id');
        const text = await page.locator('#details').innerText();
        checkReport(report);
        console.log(`pointer at (${u.toFixed(1)}, ${v.toFixed(1)}) for ${car.id}: pane shows ${shown}`);
        if (shown !== car.id || !text.includes(car.id)) {
            fail(`the details pane shows '${shown}' (${text.replace(/\n/g, ' ')}), expected ${car.id}`);
        }
        // Away from every entity (the sky above the road) the pane releases the selection.
        await page.mouse.click(k.cx, 2);
        if (await page.locator('#details').isVisible()) fail('the pane stays after a click on the sky');
    } finally {
        server.close();
        await context.close();
    }
}

fs.mkdirSync(outDir, { recursive: true });
const tests = { camera: cameraTest, pick: pickTest };
if (!tests[mode]) fail('unknown mode ' + mode);
tests[mode]().then(() => console.log('PASS'), (e) => fail(e.stack || String(e)));
