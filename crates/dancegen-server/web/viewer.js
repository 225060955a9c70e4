/**
 * The dance viewer: one three.js canvas per variation of a finished job, side by side, all
 * driven by ONE <audio> element playing the job's song.
 *
 * The audio element is the only clock. On every animation frame each variation's mixer is set
 * to `clamp(audio.currentTime - start, 0, clip.duration)` (`start` = the job's `params.start`:
 * the server cuts nothing, glb time 0 is the song at `start`), so picture and music cannot
 * drift, and pausing, scrubbing or slowing the song moves the dancers with it.
 *
 * GLB layout (crates/dancegen-formats/src/gltf.rs): one skin per dancer whose joint list is the
 * joint order of the .npy (SMPL 24); one dancer → mesh node `body`, several → mesh nodes
 * `dancer{d}` with joints `dancer{d}/<joint>`. Node names are not used for joints because
 * GLTFLoader sanitises them (`/` is dropped); joints are found by glTF node index through the
 * parser's associations instead.
 *
 * A job made with the user's character has the character's own scene instead: its bones, its
 * meshes (skinned or parented to bones), and an animation whose `extras` list the node each
 * SMPL joint drives (crates/dancegen-character/src/glb_out.rs, `dancegen_smpl_nodes`). The
 * viewer takes its one dancer's joints from that list, so framing, following, the shadow and
 * the close-up work on any rig.
 */
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

/** Download-button labels by file kind; unknown kinds show their own name. */
const FILE_LABELS = {
  glb: '3D scene (.glb)',
  fbx: 'FBX',
  bvh: 'BVH',
  npz: 'SMPL (.npz)',
  npy: 'Joints (.npy)',
  json: 'JSON',
  mp4: 'Video (.mp4)',
  csv: 'Face (.csv, ARKit 52)',
  leader_npy: 'Leader joints (.npy)',
};

/** How long a seek may take before the song is declared unseekable (e.g. no HTTP Range). */
const SEEK_TIMEOUT_MS = 10000;

/** Camera field of view, degrees. */
const FOV = 40;
/** SMPL joint indices (the skin's joint order, also SMPL-H's body): chest, head, left wrist;
 * a holistic skeleton's fingers come after the wrists. */
const CHEST_JOINT = 9;
const HEAD_JOINT = 15;
const LEFT_WRIST_JOINT = 20;
/** The close-up frames at least this much (metres a side): a face and two hands. */
const CLOSEUP_LEAST = 0.35;
/** Head sphere radius and its centre above the head joint (the base of the skull), metres. */
const HEAD_RADIUS = 0.1;
const HEAD_LIFT = 0.09;
/**
 * Contact shadow under each dancer: its radius with the feet on the floor, how much it grows
 * per metre the lowest joint is above the floor, and its darkness on the floor. A dancer in
 * the air gets a paler, wider shadow, so floating shows as it does in the MP4.
 */
const SHADOW_RADIUS = 0.32;
const SHADOW_GROWTH = 0.8;
const SHADOW_OPACITY = 0.5;
/** Height above the floor at which the shadow has faded to its palest, metres. */
const SHADOW_FADE_HEIGHT = 0.5;
/** Joints this close above a dancer's lowest one are its supporting feet (the shadow's centre). */
const SUPPORT_BAND = 0.05;
/** SMPL 24's parent joints: a joint the character has no bone for takes its parent's. */
const SMPL_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21];
/** The animation `extras` key of a character's SMPL joint nodes (dancegen_character). */
const SMPL_NODES_EXTRA = 'dancegen_smpl_nodes';

/** A soft round shadow texture (dark centre fading to nothing at the rim). */
function shadowTexture() {
  const c = document.createElement('canvas');
  c.width = c.height = 64;
  const g = c.getContext('2d');
  const r = g.createRadialGradient(32, 32, 0, 32, 32, 32);
  r.addColorStop(0, 'rgba(20,18,15,1)');
  r.addColorStop(0.55, 'rgba(20,18,15,0.55)');
  r.addColorStop(1, 'rgba(20,18,15,0)');
  g.fillStyle = r;
  g.fillRect(0, 0, 64, 64);
  const t = new THREE.CanvasTexture(c);
  t.colorSpace = THREE.SRGBColorSpace;
  return t;
}

/** Formats seconds as m:ss.s for the clock. */
export function formatTime(s) {
  const t = Math.max(0, s);
  const m = Math.floor(t / 60);
  const rest = (t - m * 60).toFixed(1).padStart(4, '0');
  return `${m}:${rest}`;
}

/** A group's per-dancer file (`bvh_0`, `npz_2`: one file per dancer) as "BVH · dancer 1". */
function dancerLabel(kind, labels) {
  const m = /^([a-z0-9]+)_(\d+)$/.exec(kind);
  return m && labels[m[1]] ? `${labels[m[1]]} · dancer ${Number(m[2]) + 1}` : null;
}

/** Download links for one file map (kind or name → URL): known kinds in the order of
 * `labels` (the 3D scene first), then the rest by name. */
export function downloadLinks(files, labels = FILE_LABELS, names = {}) {
  const known = Object.keys(labels);
  const rank = (k) => (known.includes(k) ? known.indexOf(k) : known.length);
  const entries = Object.entries(files ?? {}).sort(([a], [b]) => rank(a) - rank(b) || a.localeCompare(b));
  const frag = document.createDocumentFragment();
  for (const [kind, url] of entries) {
    const a = document.createElement('a');
    a.className = 'button download';
    a.href = url;
    // Saved as `<song>-<system>-seed<k>.<ext>` (the job's `names`), not the folder's `dance.glb`.
    a.download = names?.[kind] ?? '';
    if (names?.[kind]) a.title = `Saves as ${names[kind]}`;
    a.textContent = labels[kind] ?? dancerLabel(kind, labels) ?? kind;
    frag.append(a);
  }
  return frag;
}

/**
 * A floor grid at y = 0 (`size` metres square, a line every `step` metres, the x and z axes
 * darker). Unlike GridHelper, every line is cut into one segment per cell: a long line that
 * passes behind the camera is dropped whole by some software renderers (SwiftShader, the
 * fallback of machines without a GPU), which left the floor without its depth lines.
 */
function floorGrid(size, step) {
  const half = size / 2;
  const n = Math.round(size / step);
  const positions = [];
  const colors = [];
  const minor = new THREE.Color(0xc9c6bf);
  const axis = new THREE.Color(0x8c8c8c);
  for (let i = 0; i <= n; i++) {
    const a = -half + i * step;
    const c = Math.abs(a) < 1e-9 ? axis : minor;
    for (let k = 0; k < n; k++) {
      const b0 = -half + k * step;
      const b1 = b0 + step;
      positions.push(a, 0, b0, a, 0, b1, b0, 0, a, b1, 0, a);
      for (let v = 0; v < 4; v++) colors.push(c.r, c.g, c.b);
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.Float32BufferAttribute(colors, 3));
  return new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ vertexColors: true }));
}

/**
 * One variation: its canvas, scene, camera, orbit controls, the loaded glb and its mixer, and
 * the bones of every dancer in .npy joint order.
 */
class Stage {
  constructor(index, variation, parent) {
    this.index = index;
    this.variation = variation;
    this.figure = document.createElement('figure');
    this.figure.className = 'variation';
    const caption = document.createElement('figcaption');
    const title = document.createElement('span');
    title.className = 'title';
    // A comparison of versions labels each one (app.js); a job's variations are numbered.
    title.textContent = (variation.label ?? `Variation ${index + 1}`) + (variation.seed !== undefined ? ` · seed ${variation.seed}` : '');
    const links = document.createElement('span');
    links.className = 'downloads';
    links.append(downloadLinks(variation.files, FILE_LABELS, variation.names));
    caption.append(title, links);
    this.canvasBox = document.createElement('div');
    this.canvasBox.className = 'canvas-box';
    this.message = document.createElement('p');
    this.message.className = 'stage-message';
    this.message.textContent = 'Loading the 3D dance…';
    this.canvasBox.append(this.message);
    this.figure.append(this.canvasBox, caption);
    parent.append(this.figure);

    this.renderer = new THREE.WebGLRenderer({ antialias: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    this.renderer.setClearColor(0xf3f1ec);
    this.canvasBox.prepend(this.renderer.domElement);

    this.scene = new THREE.Scene();
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8070, 2.0));
    const sun = new THREE.DirectionalLight(0xffffff, 1.8);
    sun.position.set(2, 5, 4);
    this.scene.add(sun);
    this.grid = floorGrid(20, 0.5);
    this.scene.add(this.grid);

    this.camera = new THREE.PerspectiveCamera(FOV, 1, 0.05, 200);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.dancers = [];
    this.meshes = [];
    this.clip = null;
    this.mixer = null;
    this.action = null;
    this.helper = null;
  }

  /** Loads the glb and binds its animation; rejects with a message in words, also shown in
   * place of the picture. */
  async load() {
    try {
      await this.loadGlb();
    } catch (e) {
      this.message.textContent = e.message;
      this.message.classList.add('failed');
      throw e;
    }
  }

  async loadGlb() {
    const url = this.variation.files?.glb;
    const who = `Variation ${this.index + 1}`;
    if (!url) throw new Error(`${who} has no 3D file (.glb) to show.`);
    let gltf;
    try {
      gltf = await new GLTFLoader().loadAsync(url);
    } catch (e) {
      throw new Error(`${who}: the 3D file could not be loaded (${e?.message ?? e}).`);
    }
    this.scene.add(gltf.scene);
    this.root = gltf.scene;

    const json = gltf.parser.json;
    const smplNodes = json.animations?.[0]?.extras?.[SMPL_NODES_EXTRA];
    // The user's character: one dancer, whose meshes may be parented to its bones.
    this.character = Array.isArray(smplNodes);
    // glTF node index → the three.js object that represents it in this scene.
    const byNode = new Map();
    gltf.scene.traverse((o) => {
      const a = gltf.parser.associations.get(o);
      if (a && a.nodes !== undefined && !byNode.has(a.nodes)) byNode.set(a.nodes, o);
      if (o.isSkinnedMesh || (this.character && o.isMesh)) {
        // Its bounding sphere is the rest pose's; a dancer who travels away from it would be
        // culled while still in view.
        o.frustumCulled = false;
        this.meshes.push(o);
      }
    });
    const node = async (i) => byNode.get(i) ?? gltf.parser.getDependency('node', i);
    if (this.character) {
      const bones = [];
      for (let j = 0; j < SMPL_PARENTS.length; j++) {
        const i = smplNodes[j];
        if (Number.isInteger(i)) bones.push(await node(i));
        else if (j > 0) bones.push(bones[SMPL_PARENTS[j]]);
        else throw new Error(`${who}: the character's file names no bone for the hips.`);
      }
      this.dancers.push(bones);
    }
    // Dancer d's skin: the skin of mesh node `dancer{d}` (`body` for a single dancer); files
    // without those names fall back to skin order, which is the same by construction.
    const skinOf = [];
    (json.nodes ?? []).forEach((n) => {
      if (n.skin === undefined) return;
      const m = /^dancer(\d+)$/.exec(n.name ?? '');
      const d = m ? Number(m[1]) : n.name === 'body' ? 0 : null;
      if (d !== null && skinOf[d] === undefined) skinOf[d] = n.skin;
    });
    const skins = this.character ? [] : json.skins ?? [];
    const order = skinOf.length === skins.length && !skinOf.includes(undefined) ? skinOf : skins.map((_, i) => i);
    for (const s of order) {
      const bones = [];
      for (const nodeIndex of skins[s].joints) bones.push(await node(nodeIndex));
      this.dancers.push(bones);
    }
    if (this.dancers.length === 0) throw new Error(`${who}: the 3D file has no skeleton.`);

    this.clip = gltf.animations[0] ?? null;
    this.mixer = new THREE.AnimationMixer(gltf.scene);
    if (this.clip) {
      // LoopOnce + clamp: time past the end holds the last pose instead of wrapping to 0.
      this.action = this.mixer.clipAction(this.clip);
      this.action.setLoop(THREE.LoopOnce, 1);
      this.action.clampWhenFinished = true;
      this.action.play();
    }

    this.helper = new THREE.SkeletonHelper(gltf.scene);
    this.helper.setColors(new THREE.Color(0x1f1d1a), new THREE.Color(0xc8581f));
    this.helper.visible = false;
    this.scene.add(this.helper);
    this.addHeadsAndShadows();
    this.addLegend();
    this.message.remove();
    this.frame();
  }

  /** The skinned body that dancer `d`'s bones move (its material gives the dancer's colour). */
  bodyOf(d) {
    if (this.character) return null;
    const root = this.dancers[d][0];
    return this.meshes.find((m) => m.skeleton?.bones.includes(root)) ?? this.meshes[d] ?? null;
  }

  /**
   * A head on every figure (a sphere on the head bone, in the body's colour: the capsule body
   * ends at the neck) and a contact shadow under it on the floor ([`updateShadows`]).
   */
  addHeadsAndShadows() {
    const texture = shadowTexture();
    this.heads = [];
    // A holistic dance brings its own head: a face mesh with the 52 ARKit morph targets.
    this.face = null;
    this.root.traverse((o) => { if (o.isMesh && o.morphTargetDictionary && !this.face) this.face = o; });
    this.shadows = this.dancers.map((bones, d) => {
      const body = this.bodyOf(d);
      // The head bone under any rig's name (three.js drops the '/' of `dancer{d}/head` and
      // the ':' of `mixamorig:Head`).
      const head = bones.find((b) => /head$/i.test(b.name ?? ''));
      if (head && body && !this.face) {
        const sphere = new THREE.Mesh(new THREE.SphereGeometry(HEAD_RADIUS, 24, 16), body.material);
        sphere.position.set(0, HEAD_LIFT, 0);
        sphere.name = 'head-sphere';
        head.add(sphere);
        this.heads.push(sphere);
      }
      const shadow = new THREE.Mesh(
        new THREE.CircleGeometry(1, 40),
        new THREE.MeshBasicMaterial({ map: texture, transparent: true, depthWrite: false, opacity: SHADOW_OPACITY }),
      );
      shadow.rotation.x = -Math.PI / 2;
      shadow.renderOrder = 1;
      shadow.name = 'contact-shadow';
      this.scene.add(shadow);
      return shadow;
    });
  }

  /**
   * Each shadow under its dancer's supporting feet (the joints within a few centimetres of its
   * lowest one), wider and paler the higher that lowest joint is above the floor.
   */
  updateShadows() {
    if (!this.shadows) return;
    this.root.updateMatrixWorld(true);
    this.dancers.forEach((bones, d) => {
      const at = bones.map((b) => b.getWorldPosition(new THREE.Vector3()));
      const lowest = Math.min(...at.map((p) => p.y));
      const height = Math.max(0, lowest);
      const feet = at.filter((p) => p.y <= lowest + SUPPORT_BAND);
      const x = feet.reduce((a, p) => a + p.x, 0) / feet.length;
      const z = feet.reduce((a, p) => a + p.z, 0) / feet.length;
      const s = this.shadows[d];
      s.position.set(x, 0.003, z);
      s.scale.setScalar(SHADOW_RADIUS + SHADOW_GROWTH * height);
      const fade = Math.min(height / SHADOW_FADE_HEIGHT, 1);
      s.material.opacity = SHADOW_OPACITY * (1 - 0.75 * fade);
    });
  }

  /**
   * Who is who, over the picture: in a duet the given leader and the generated partner, in a
   * group each dancer's number, each with its body's colour.
   */
  addLegend() {
    const names = this.variation.dancerNames;
    if (!names || names.length !== this.dancers.length) return;
    const legend = document.createElement('ul');
    legend.className = 'legend';
    names.forEach((name, d) => {
      const li = document.createElement('li');
      const dot = document.createElement('span');
      dot.className = 'dot';
      const colour = this.bodyOf(d)?.material?.color;
      if (colour) dot.style.background = `#${colour.getHexString(THREE.SRGBColorSpace)}`;
      li.append(dot, document.createTextNode(name));
      legend.append(li);
    });
    this.canvasBox.append(legend);
  }

  /** Length of the dance, seconds. */
  get duration() {
    return this.clip ? this.clip.duration : 0;
  }

  /** Poses every dancer at dance time `t` (seconds from the glb's time 0). */
  pose(t) {
    if (!this.action) return;
    const clamped = Math.min(Math.max(t, 0), this.clip.duration);
    // A LoopOnce action pauses itself at the end; setTime must be able to go back.
    this.action.paused = false;
    this.action.enabled = true;
    this.mixer.setTime(clamped);
    this.updateShadows();
  }

  /** World positions of every joint: [dancer][joint] = [x, y, z]. */
  joints() {
    this.scene.updateMatrixWorld(true);
    const p = new THREE.Vector3();
    return this.dancers.map((bones) => bones.map((b) => b.getWorldPosition(p).toArray()));
  }

  /** Mean world position of the dancers' root joints. */
  rootCentroid(out = new THREE.Vector3()) {
    out.set(0, 0, 0);
    const p = new THREE.Vector3();
    for (const bones of this.dancers) out.add(bones[0].getWorldPosition(p));
    return out.divideScalar(Math.max(1, this.dancers.length));
  }

  /**
   * Boxes around every joint over the whole clip (sampled), for framing: `world`, where the
   * dancers go (the fixed views keep dancers who travel in view), and `around`, the same taken
   * horizontally from the dancers' root centroid at each moment (heights as they are), which
   * the follow camera frames: the dancers large, wherever they are.
   */
  motionBounds() {
    const world = new THREE.Box3();
    const around = new THREE.Box3();
    const now = new THREE.Box3();
    const p = new THREE.Vector3();
    const samples = 24;
    for (let i = 0; i <= samples; i++) {
      this.pose((this.duration * i) / samples);
      this.root.updateMatrixWorld(true);
      now.makeEmpty();
      for (const bones of this.dancers) for (const b of bones) now.expandByPoint(b.getWorldPosition(p));
      for (const h of this.heads ?? []) now.expandByPoint(h.getWorldPosition(p).setY(p.y + HEAD_RADIUS));
      // A character's head, hands and feet reach past its bones (the robot's head is as
      // large as its body): frame its meshes as posed.
      if (this.character) for (const m of this.meshes) now.expandByObject(m);
      world.union(now);
      around.union(now.translate(this.floorCentroid().negate()));
    }
    this.pose(0);
    return { world, around };
  }

  /** The dancers' root centroid on the floor (y = 0), where the follow camera looks. */
  floorCentroid() {
    return this.rootCentroid().setY(0);
  }

  /**
   * Frames `view` for the follow camera: the `around` box placed on the dancers now, and the
   * offset of the camera's target from their centroid kept from then on ([`follow`]).
   */
  frameFollowing(view, around) {
    this.root.updateMatrixWorld(true);
    const c = this.floorCentroid();
    this.setView(view, around.clone().translate(c));
    this.followOffset = this.controls.target.clone().sub(c);
  }

  /**
   * Places the camera for a preset so that `box` fills the view, a little from above; a box
   * smaller than `least` metres a side is framed as that large.
   */
  setView(view, box, least = 0.8) {
    const size = box.getSize(new THREE.Vector3()).max(new THREE.Vector3(least, least, least));
    const target = box.getCenter(new THREE.Vector3());
    // Across and up the picture, and along the line of sight, for each preset.
    const [across, up, depth] = { side: [size.z, size.y, size.x], top: [size.x, size.z, size.y] }[view]
      ?? [size.x, size.y, size.z];
    const tanV = Math.tan(THREE.MathUtils.degToRad(FOV) / 2);
    const fit = Math.max(up / 2 / tanV, across / 2 / (tanV * this.camera.aspect));
    const dist = (depth / 2 + fit) * 1.1;
    const lift = Math.sin(THREE.MathUtils.degToRad(12)) * dist;
    const flat = Math.cos(THREE.MathUtils.degToRad(12)) * dist;
    const offset = {
      side: new THREE.Vector3(flat, lift, 0),
      // Straight down, nudged so OrbitControls keeps a defined "up".
      top: new THREE.Vector3(0, dist, 0.001 * dist),
    }[view] ?? new THREE.Vector3(0, lift, flat);
    this.controls.target.copy(target);
    this.camera.position.copy(target).add(offset);
    this.camera.lookAt(target);
    this.controls.update();
  }

  /**
   * The first dancer's head and hands now (head joint, wrists and every finger bone, and the
   * face mesh), a little enlarged: what the close-up frames.
   */
  closeupBox() {
    const bones = this.dancers[0];
    const box = new THREE.Box3();
    const p = new THREE.Vector3();
    this.root.updateMatrixWorld(true);
    bones.forEach((b, j) => {
      if (j === CHEST_JOINT || j === HEAD_JOINT || j >= LEFT_WRIST_JOINT) box.expandByPoint(b.getWorldPosition(p));
    });
    if (this.face) box.expandByObject(this.face);
    return box.expandByScalar(0.08);
  }

  /** Moves camera and target together so the target sits on the first dancer's chest. */
  followChest() {
    const c = this.dancers[0][CHEST_JOINT].getWorldPosition(new THREE.Vector3());
    const delta = c.sub(this.controls.target);
    if (delta.lengthSq() < 1e-12) return;
    this.controls.target.add(delta);
    this.camera.position.add(delta);
    this.controls.update();
  }

  /**
   * Moves camera and target together, along the floor, so the target keeps its place over the
   * dancers' root centroid: the camera travels with them, and a jump or a crouch still shows
   * against the floor.
   */
  follow() {
    const c = this.floorCentroid().add(this.followOffset ?? new THREE.Vector3());
    const delta = c.sub(this.controls.target).setY(0);
    if (delta.lengthSq() < 1e-12) return;
    this.controls.target.add(delta);
    this.camera.position.add(delta);
    this.controls.update();
  }

  /** Resizes the drawing buffer to the box the page gives the canvas. */
  resize() {
    const w = Math.max(1, this.canvasBox.clientWidth);
    const h = Math.max(1, this.canvasBox.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
  }

  frame() {
    this.renderer.render(this.scene, this.camera);
  }

  showSkeleton(on) {
    if (this.helper) this.helper.visible = on;
    for (const m of this.meshes) m.visible = !on;
  }

  dispose() {
    this.renderer.setAnimationLoop(null);
    this.controls.dispose();
    this.helper?.dispose();
    this.renderer.dispose();
    this.figure.remove();
  }
}

/**
 * The whole viewer for one done job. `root` is the #viewer element of index.html, whose
 * controls (play, scrub, speed, views, toggles) it wires. `ready` resolves when the song's
 * metadata and every variation's glb are loaded and rejects with a message in words.
 */
export class Viewer {
  constructor(root, job) {
    this.root = root;
    this.start = Number(job.params?.start) || 0;
    this.el = {
      play: root.querySelector('#play'),
      scrub: root.querySelector('#scrub'),
      clock: root.querySelector('#clock'),
      box: root.querySelector('#variations-box'),
      skeleton: root.querySelector('#show-skeleton'),
      grid: root.querySelector('#show-grid'),
      loop: root.querySelector('#loop'),
      fullscreen: root.querySelector('#fullscreen'),
      waveform: root.querySelector('#waveform'),
    };
    this.timelineUrl = job.timeline ?? null;
    // The close-up on the head and hands is for a dance with fingers and a face.
    const closeup = root.querySelector('.view[data-view="closeup"]');
    if (closeup) closeup.hidden = job.params?.system !== 'holistic';
    this.timeline = null;
    this.audio = document.createElement('audio');
    this.audio.preload = 'auto';
    this.audio.className = 'song';
    root.append(this.audio);
    // Who is who in the picture's legend: a duet's given leader and generated partner (the
    // .glb holds the leader first), a group's dancers by number.
    const system = job.params?.system;
    const dancers = Number(job.params?.dancers) || 0;
    const dancerNames = system === 'duet' ? ['Leader (given)', 'Partner (generated)']
      : system === 'group' && dancers > 1 ? Array.from({ length: dancers }, (_, d) => `Dancer ${d + 1}`)
        : null;
    this.stages = (job.variations ?? []).map((v, i) => new Stage(i, { ...v, dancerNames }, this.el.box));
    this.root.style.setProperty('--variations', String(Math.max(1, this.stages.length)));
    this.duration = 0;
    this.view = 'front';
    this.following = false;
    this.dirty = true;
    this.lastTime = NaN;
    this.scrubbing = false;
    this.syncing = false;
    this.listeners = [];

    if (this.stages.length === 0) {
      this.ready = Promise.reject(new Error('This job has no dances to show.'));
    } else {
      const songReady = this.loadSong(job.song);
      const glbsReady = Promise.all(this.stages.map((s) => s.load()));
      this.ready = Promise.all([songReady, glbsReady]).then(() => this.begin());
    }
  }

  /** Number of variations. */
  get count() {
    return this.stages.length;
  }

  /** Resolves once the song's length is known; rejects in words if it cannot be played. */
  loadSong(url) {
    if (!url) return Promise.reject(new Error('This job has no song to play.'));
    return new Promise((resolve, reject) => {
      const a = this.audio;
      const ok = () => { off(); resolve(); };
      const bad = () => {
        off();
        const code = a.error?.code;
        const why = code === 4 ? 'this browser cannot play its format'
          : code === 2 ? 'the network failed while loading it'
          : code === 3 ? 'it could not be decoded'
          : a.error?.message || 'unknown reason';
        reject(new Error(`The song could not be loaded: ${why}.`));
      };
      const off = () => { a.removeEventListener('loadedmetadata', ok); a.removeEventListener('error', bad); };
      a.addEventListener('loadedmetadata', ok);
      a.addEventListener('error', bad);
      a.src = url;
    });
  }

  /** After everything loaded: frame the dancers, wire the controls, start the frame loop. */
  async begin() {
    this.duration = Math.max(...this.stages.map((s) => s.duration));
    // One framing for all variations, so that side by side they are seen at the same scale.
    const bounds = new THREE.Box3();
    const around = new THREE.Box3();
    for (const s of this.stages) {
      const b = s.motionBounds();
      bounds.union(b.world);
      around.union(b.around);
    }
    for (const s of this.stages) {
      s.bounds = bounds;
      s.around = around;
      s.resize();
      s.controls.addEventListener('change', () => this.cameraMoved(s));
    }
    // The dancers framed large from the front, followed as they travel.
    this.following = true;
    this.frameStages();
    this.wireControls();
    await this.loadTimeline();
    const ro = new ResizeObserver(() => {
      for (const s of this.stages) s.resize();
      this.drawTimeline(this.danceTime());
      this.dirty = true;
    });
    for (const s of this.stages) ro.observe(s.canvasBox);
    this.resizeObserver = ro;
    if (this.start > 0) await this.seek(this.start);
    // One loop for all canvases: every variation is posed from the same clock reading.
    this.stages[0].renderer.setAnimationLoop(() => this.tick());
    this.tick();
  }

  /**
   * A user orbited, panned or zoomed in one canvas: the others take the same camera, so the
   * variations stay comparable. Moves made by the viewer itself (presets, follow) are not
   * copied, which `syncing` marks.
   */
  cameraMoved(source) {
    this.dirty = true;
    if (this.syncing) return;
    this.syncing = true;
    for (const s of this.stages) {
      if (s === source) continue;
      s.camera.position.copy(source.camera.position);
      s.controls.target.copy(source.controls.target);
      s.controls.update();
    }
    this.syncing = false;
  }

  /** Dance time now: the song's time minus the dance's start in the song. */
  danceTime() {
    return Math.min(Math.max(this.audio.currentTime - this.start, 0), this.duration);
  }

  /**
   * One animation frame: pose every variation from the audio clock and render — only when
   * the time or the view changed, so a paused viewer costs no CPU.
   */
  tick(force = false) {
    const a = this.audio;
    if (!a.paused && a.currentTime - this.start >= this.duration) {
      // The dance is over: from its start again with Loop, else stop (the rest of the song
      // would show a frozen pose).
      if (this.el.loop?.checked) a.currentTime = this.start;
      else a.pause();
    }
    const t = this.danceTime();
    const moved = t !== this.lastTime;
    if (!(moved || this.dirty || force)) return;
    for (const s of this.stages) s.pose(t);
    if (this.following || this.view === 'closeup') {
      this.syncing = true;
      for (const s of this.stages) {
        s.root.updateMatrixWorld(true);
        if (this.view === 'closeup') s.followChest();
        else s.follow();
      }
      this.syncing = false;
    }
    for (const s of this.stages) s.frame();
    if (moved) {
      this.drawTimeline(t);
      this.el.clock.textContent = `${formatTime(t)} / ${formatTime(this.duration)}`;
      if (!this.scrubbing) this.el.scrub.value = String(this.start + t);
    }
    this.lastTime = t;
    this.dirty = false;
  }

  /**
   * The waveform and beats under the scrub bar (`timeline.json`, written by the server); a
   * job without one (an older job) simply has no waveform. Clicking it goes there.
   */
  async loadTimeline() {
    const canvas = this.el.waveform;
    if (!canvas || !this.timelineUrl) return;
    try {
      const res = await fetch(this.timelineUrl);
      if (!res.ok) return;
      const t = await res.json();
      if (!Array.isArray(t.peaks) || !Array.isArray(t.beats)) return;
      this.timeline = t;
    } catch {
      return;
    }
    canvas.hidden = false;
    const click = (e) => {
      const r = canvas.getBoundingClientRect();
      const u = Math.min(Math.max((e.clientX - r.left) / Math.max(r.width, 1), 0), 1);
      this.seek(this.start + u * this.duration).catch((err) => this.onError?.(err));
    };
    canvas.addEventListener('click', click);
    this.listeners.push(() => {
      canvas.removeEventListener('click', click);
      canvas.hidden = true;
    });
    this.drawTimeline(this.danceTime());
  }

  /** Draws the waveform (the part played so far in the accent colour) and the beats at `t`. */
  drawTimeline(t) {
    const canvas = this.el.waveform;
    const tl = this.timeline;
    if (!canvas || !tl || canvas.hidden) return;
    const dpr = Math.min(window.devicePixelRatio || 1, 2);
    const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
    const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    const g = canvas.getContext('2d');
    g.clearRect(0, 0, w, h);
    const length = Math.max(tl.duration || this.duration, 1e-6);
    const played = (t / length) * w;
    const n = tl.peaks.length;
    for (let x = 0; x < w; x++) {
      const peak = tl.peaks[Math.min(n - 1, Math.floor((x / w) * n))] || 0;
      const bar = Math.max(1, peak * (h - 6));
      g.fillStyle = x < played ? '#c8581f' : '#b9b4aa';
      g.fillRect(x, (h - bar) / 2, 1, bar);
    }
    g.fillStyle = '#1f1d1a';
    for (const b of tl.beats) {
      const x = Math.round((b / length) * w);
      g.fillRect(x, 0, Math.max(1, dpr), 3 * dpr);
      g.fillRect(x, h - 3 * dpr, Math.max(1, dpr), 3 * dpr);
    }
  }

  /**
   * The first variation's camera against the first dancer's head (the browser test reads it
   * after choosing a view): distance, whether the head is in the picture, whether the file has
   * a face and whether a head sphere was added.
   */
  cameraInfo() {
    const s = this.stages[0];
    s.scene.updateMatrixWorld(true);
    const head = s.dancers[0][HEAD_JOINT].getWorldPosition(new THREE.Vector3());
    const ndc = head.clone().project(s.camera);
    return {
      view: this.view,
      distance: s.camera.position.distanceTo(head),
      headInView: Math.abs(ndc.x) < 1 && Math.abs(ndc.y) < 1 && ndc.z < 1,
      face: Boolean(s.face),
      headSpheres: s.heads?.length ?? 0,
      following: this.following,
      // Every dancer's joints inside the picture, of all of them.
      jointsInView: s.dancers.flat().filter((b) => {
        const q = b.getWorldPosition(new THREE.Vector3()).project(s.camera);
        return Math.abs(q.x) < 1 && Math.abs(q.y) < 1 && q.z < 1;
      }).length,
      joints: s.dancers.flat().length,
      target: s.controls.target.toArray(),
      centroid: s.floorCentroid().toArray(),
    };
  }

  /** What the timeline shows (the browser test reads it). */
  timelineInfo() {
    const canvas = this.el.waveform;
    const tl = this.timeline;
    let inked = 0;
    if (canvas && !canvas.hidden && canvas.width > 0) {
      const px = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
      for (let i = 3; i < px.length; i += 4) if (px[i] > 0) inked++;
    }
    return {
      shown: Boolean(canvas && !canvas.hidden),
      beats: tl?.beats.length ?? 0,
      peaks: tl?.peaks.length ?? 0,
      firstBeat: tl?.beats[0] ?? null,
      lastBeat: tl?.beats[tl.beats.length - 1] ?? null,
      duration: tl?.duration ?? null,
      inked,
    };
  }

  /** Seeks the song to `t` (song seconds), waits for the audio to get there, poses, renders. */
  seek(t) {
    const a = this.audio;
    return new Promise((resolve, reject) => {
      const timer = setTimeout(() => {
        off();
        reject(new Error(`Seeking the song to ${t} s did not finish (does the server answer HTTP Range requests?).`));
      }, SEEK_TIMEOUT_MS);
      const done = () => {
        off();
        this.tick(true);
        resolve({ audio: a.currentTime, dance: this.danceTime() });
      };
      const off = () => { clearTimeout(timer); a.removeEventListener('seeked', done); };
      a.addEventListener('seeked', done);
      a.currentTime = t;
    });
  }

  /** Plays from where the song is; at the end of the dance it starts again from the top. */
  play() {
    const a = this.audio;
    if (a.currentTime < this.start || a.currentTime - this.start >= this.duration - 1e-3) a.currentTime = this.start;
    return a.play();
  }

  /** World joint positions of variation `v`: [dancer][joint][x, y, z]. */
  joints(v = 0) {
    const s = this.stages[v];
    if (!s) throw new Error(`no variation ${v} (there are ${this.stages.length})`);
    return s.joints();
  }

  /**
   * What variation `v` draws around its joints (the browser test reads it): the head spheres'
   * centres, each dancer's contact shadow (floor position, radius, opacity), pelvis and lowest
   * joint height, and the legend's lines.
   */
  figures(v = 0) {
    const s = this.stages[v];
    if (!s) throw new Error(`no variation ${v} (there are ${this.stages.length})`);
    s.scene.updateMatrixWorld(true);
    const p = new THREE.Vector3();
    return {
      heads: (s.heads ?? []).map((h) => h.getWorldPosition(p).toArray()),
      shadows: (s.shadows ?? []).map((m) => ({ at: [m.position.x, m.position.y, m.position.z], radius: m.scale.x, opacity: m.material.opacity })),
      pelvis: s.dancers.map((bones) => bones[0].getWorldPosition(p).toArray()),
      lowest: s.dancers.map((bones) => Math.min(...bones.map((b) => b.getWorldPosition(p).y))),
      legend: [...s.canvasBox.querySelectorAll('.legend li')].map((li) => li.textContent),
    };
  }

  /**
   * A preset (front, side, top, close-up: fixed framings of where the dancers go) or Follow,
   * which turns the follow camera on or off in the current preset's direction.
   */
  setView(view) {
    if (view === 'follow') {
      this.following = !this.following;
    } else {
      this.following = false;
      this.view = view;
    }
    this.frameStages();
  }

  /** Places every variation's camera for the current view and follow state. */
  frameStages() {
    this.syncing = true;
    for (const s of this.stages) {
      // The close-up frames the head and hands from the front and then follows the chest.
      if (this.view === 'closeup') s.setView('front', s.closeupBox(), CLOSEUP_LEAST);
      else if (this.following) s.frameFollowing(this.view, s.around);
      else s.setView(this.view, s.bounds);
    }
    this.syncing = false;
    this.dirty = true;
    for (const b of this.root.querySelectorAll('.view')) {
      const on = b.dataset.view === 'follow' ? this.following : b.dataset.view === 'closeup' && this.view === 'closeup';
      b.setAttribute('aria-pressed', String(on));
    }
    this.dirty = true;
  }

  /** Wires the buttons of index.html's #viewer to this viewer (undone by dispose). */
  wireControls() {
    const on = (target, type, fn) => {
      target.addEventListener(type, fn);
      this.listeners.push(() => target.removeEventListener(type, fn));
    };
    const { play, scrub } = this.el;
    const a = this.audio;
    play.disabled = false;
    scrub.disabled = false;
    scrub.min = String(this.start);
    scrub.max = String(this.start + this.duration);
    scrub.step = String(1 / 30);
    on(play, 'click', () => {
      if (a.paused) this.play().catch((e) => this.onError?.(new Error(`The song cannot play: ${e.message}`)));
      else a.pause();
    });
    const label = () => { play.textContent = a.paused ? 'Play' : 'Pause'; };
    on(a, 'play', label);
    on(a, 'pause', label);
    on(scrub, 'pointerdown', () => { this.scrubbing = true; });
    on(scrub, 'pointerup', () => { this.scrubbing = false; });
    on(scrub, 'change', () => { this.scrubbing = false; });
    on(scrub, 'input', () => { a.currentTime = Number(scrub.value); });
    for (const b of this.root.querySelectorAll('.speed')) {
      on(b, 'click', () => {
        a.playbackRate = Number(b.dataset.rate);
        for (const o of this.root.querySelectorAll('.speed')) o.setAttribute('aria-pressed', String(o === b));
      });
    }
    for (const b of this.root.querySelectorAll('.view')) on(b, 'click', () => this.setView(b.dataset.view));
    // The variations over the whole screen; the browser's Esc leaves.
    const fs = this.el.fullscreen;
    if (fs) {
      fs.hidden = !document.fullscreenEnabled;
      on(fs, 'click', () => {
        if (document.fullscreenElement) document.exitFullscreen().catch(() => {});
        else this.el.box.requestFullscreen().catch((e) => this.onError?.(new Error(`Full screen was refused: ${e.message}`)));
      });
      on(document, 'fullscreenchange', () => {
        fs.textContent = document.fullscreenElement ? 'Leave full screen' : 'Full screen';
      });
    }
    on(this.el.skeleton, 'change', () => {
      for (const s of this.stages) s.showSkeleton(this.el.skeleton.checked);
      this.dirty = true;
    });
    on(this.el.grid, 'change', () => {
      for (const s of this.stages) s.grid.visible = this.el.grid.checked;
      this.dirty = true;
    });
    // Space bar plays and pauses, except while typing or pressing a focused button.
    on(document, 'keydown', (e) => {
      if (e.code !== 'Space' || e.target.closest?.('input, select, textarea, button, a')) return;
      e.preventDefault();
      play.click();
    });
  }

  dispose() {
    for (const off of this.listeners) off();
    this.resizeObserver?.disconnect();
    for (const s of this.stages) s.dispose();
    this.audio.pause();
    this.audio.removeAttribute('src');
    this.audio.load();
    this.audio.remove();
    this.el.play.disabled = true;
    this.el.scrub.disabled = true;
  }
}
