// A third-party Foxglove protocol client against a live tyrerig suite.
//
// `tyrerig run --foxglove` runs the whole suite over DDS (virtual rig in lockstep) with the
// foxglove node serving it. This test connects with Foxglove's own protocol client
// (@foxglove/ws-protocol), lists the channels, decodes RigSample and ThermalState with Foxglove's
// ROS 2 CDR decoder (@foxglove/rosmsg + @foxglove/rosmsg2-serialization) from the schemas the
// server advertises, and compares them field by field with the MCAP log the recorder wrote of the
// same run (read with @mcap/core). It sends PAUSE and RESUME (allowed) and sees the procedure
// pause and go on, and ESTOP (not allowed) and sees it refused. A stuck client (socket never
// read) rides along: the suite must not notice it. Run inside scripts/netns-run (DDS on loopback
// only); TYRERIG_BIN names the binary.

import { test } from "node:test";
import assert from "node:assert/strict";
import { spawn } from "node:child_process";
import { mkdtempSync, rmSync } from "node:fs";
import { open } from "node:fs/promises";
import { tmpdir } from "node:os";
import { join, resolve, dirname } from "node:path";
import { fileURLToPath } from "node:url";
import WebSocket from "ws";
import wsProtocol from "@foxglove/ws-protocol";
import { parse } from "@foxglove/rosmsg";
import { MessageReader, MessageWriter } from "@foxglove/rosmsg2-serialization";
import { McapIndexedReader } from "@mcap/core";
import { decompress } from "fzstd";

// The package is CommonJS: its named exports sit on the default export under Node's ESM loader.
const { FoxgloveClient } = wsProtocol;
const here = dirname(fileURLToPath(import.meta.url));
const repo = resolve(here, "../..");
const BIN = process.env.TYRERIG_BIN ?? join(repo, "target/release/tyrerig");
const PORT = Number(process.env.TYRERIG_FOXGLOVE_PORT ?? 18765);
const NS = "/rig";

const PHASE_SWEEP = 1;
const PHASE_PAUSED = 5;
const PHASE_COMPLETE = 8;
const PAUSE = 1;
const RESUME = 2;
const ESTOP = 4;

const SUITE_TOPICS = {
  [`${NS}/sample`]: "tyre_msgs/msg/RigSample",
  [`${NS}/setpoint`]: "tyre_msgs/msg/RigSetpoint",
  [`${NS}/procedure/state`]: "tyre_msgs/msg/ProcedureState",
  [`${NS}/procedure/command`]: "tyre_msgs/msg/ProcedureCommand",
  [`${NS}/thermal/state`]: "tyre_msgs/msg/ThermalState",
  [`${NS}/channels/live`]: "tyre_msgs/msg/LiveChannels",
  [`${NS}/channels/sweep_summary`]: "tyre_msgs/msg/SweepSummary",
  [`${NS}/channels/derived`]: "tyre_msgs/msg/DerivedMeasurement",
  [`${NS}/quality/report`]: "tyre_msgs/msg/QualityReport",
  "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
  "/clock": "rosgraph_msgs/msg/Clock",
};
const VIEW_TOPICS = ["plan", "progress", "sweep_trace", "sweep_trace_previous", "alarms", "model"].map(
  (v) => `${NS}/foxglove/${v}`,
);

// The SDK's server names its protocol `foxglove.sdk.v1` (the Foxglove app offers it); its messages
// are the Foxglove WebSocket protocol that @foxglove/ws-protocol's client speaks, which is handed a
// socket opened with that name (the client itself only reads and writes the messages).
const SUBPROTOCOL = "foxglove.sdk.v1";

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function waitFor(what, predicate, timeoutMs) {
  const end = Date.now() + timeoutMs;
  while (Date.now() < end) {
    const v = predicate();
    if (v) return v;
    await sleep(50);
  }
  throw new Error(`timed out after ${timeoutMs} ms waiting for ${what}`);
}

/** Connects a FoxgloveClient (and its watcher), retrying while the suite starts. The client and
 * the watcher's listeners exist before the socket opens: the server sends its channel list right
 * after the handshake, possibly in the same packet. */
async function connect(url, timeoutMs, why = () => "") {
  const end = Date.now() + timeoutMs;
  for (;;) {
    const ws = new WebSocket(url, [SUBPROTOCOL]);
    const client = new FoxgloveClient({ ws });
    const w = watch(client);
    const opened = await new Promise((res) => {
      client.on("open", () => res(true));
      client.on("error", () => res(false));
    });
    if (opened) return { client, ws, w };
    client.close();
    if (Date.now() > end) throw new Error(`no Foxglove server at ${url}\n${why()}`);
    await sleep(200);
  }
}

/** Watches one client: channels as advertised, decoded messages per topic, statuses. */
function watch(client) {
  const w = { channels: new Map(), byTopic: new Map(), subs: new Map(), readers: new Map(), statuses: [] };
  // Listen at once: the server advertises right after the handshake.
  client.on("advertise", (chs) => chs.forEach((c) => w.channels.set(c.topic, c)));
  client.on("status", (s) => w.statuses.push(s));
  client.on("message", ({ subscriptionId, data }) => {
    const topic = w.subs.get(subscriptionId);
    const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
    const msg = w.readers.get(topic)(bytes);
    if (!w.byTopic.has(topic)) w.byTopic.set(topic, []);
    w.byTopic.get(topic).push(msg);
  });
  w.subscribe = (topic) => {
    const ch = w.channels.get(topic);
    assert.ok(ch, `no channel ${topic}`);
    if (ch.encoding === "cdr") {
      const reader = new MessageReader(parse(ch.schema, { ros2: true }));
      w.readers.set(topic, (b) => reader.readMessage(b));
    } else {
      const text = new TextDecoder();
      w.readers.set(topic, (b) => JSON.parse(text.decode(b)));
    }
    w.subs.set(client.subscribe(ch.id), topic);
  };
  w.got = (topic) => w.byTopic.get(topic) ?? [];
  return w;
}

/** Every message of `topic` in the MCAP log, decoded from the log's own schema. */
async function readLog(path, topics) {
  const handle = await open(path, "r");
  const readable = {
    size: async () => BigInt((await handle.stat()).size),
    read: async (offset, length) => {
      const buf = Buffer.alloc(Number(length));
      await handle.read(buf, 0, Number(length), Number(offset));
      return buf;
    },
  };
  const reader = await McapIndexedReader.Initialize({
    readable,
    decompressHandlers: { zstd: (data, size) => decompress(data, new Uint8Array(Number(size))) },
  });
  const decoders = new Map();
  const out = new Map(topics.map((t) => [t, []]));
  for await (const m of reader.readMessages({ topics })) {
    const ch = reader.channelsById.get(m.channelId);
    if (!decoders.has(ch.id)) {
      const schema = reader.schemasById.get(ch.schemaId);
      assert.equal(schema.encoding, "ros2msg");
      decoders.set(ch.id, new MessageReader(parse(new TextDecoder().decode(schema.data), { ros2: true })));
    }
    out.get(ch.topic).push(decoders.get(ch.id).readMessage(m.data));
  }
  await handle.close();
  return out;
}

const stampKey = (h) => `${h.stamp.sec}.${h.stamp.nanosec}`;

test("a Foxglove protocol client watches a DDS run, decodes it as the MCAP log has it, and pauses it", async (t) => {
  const dir = mkdtempSync(join(tmpdir(), "tyrerig-foxglove-"));
  t.after(() => rmSync(dir, { recursive: true, force: true }));
  const log = join(dir, "run.mcap");
  const suite = spawn(
    BIN,
    [
      "run",
      "--procedure", "staticlong",
      "--seed", "3",
      "--quiet",
      "--launch-config", join(repo, "launch-config"),
      "--out", log,
      "--foxglove", String(PORT),
      "--foxglove-allow", "PAUSE,RESUME",
    ],
    { stdio: ["ignore", "pipe", "pipe"] },
  );
  let stderr = "";
  suite.stderr.on("data", (d) => (stderr += d));
  suite.stdout.on("data", () => {});
  const exited = new Promise((res) => suite.on("exit", (code) => res(code)));
  t.after(() => suite.exitCode === null && suite.kill("SIGTERM"));

  const url = `ws://127.0.0.1:${PORT}`;
  const { client, ws, w } = await connect(url, 60_000, () => `tyrerig exit ${suite.exitCode}:\n${stderr.slice(-3000)}`);

  // A stuck browser: subscribes to the 1 kHz samples and never reads its socket again.
  const stuck = new WebSocket(url, [SUBPROTOCOL]);
  const stuckChannels = [];
  stuck.on("message", (data, isBinary) => {
    if (isBinary) return;
    const m = JSON.parse(data.toString());
    if (m.op === "advertise") stuckChannels.push(...m.channels);
  });

  // Every suite topic with its ROS 2 schema and CDR, and the views in JSON.
  await waitFor("every channel advertised", () => w.channels.size >= 16 && stuckChannels.length >= 16, 30_000);
  for (const [topic, type] of Object.entries(SUITE_TOPICS)) {
    const ch = w.channels.get(topic);
    assert.ok(ch, `channel ${topic} advertised`);
    assert.equal(ch.encoding, "cdr", topic);
    assert.equal(ch.schemaName, type, topic);
    assert.equal(ch.schemaEncoding, "ros2msg", topic);
    assert.doesNotThrow(() => parse(ch.schema, { ros2: true }), topic);
  }
  for (const topic of VIEW_TOPICS) {
    assert.equal(w.channels.get(topic)?.encoding, "json", topic);
  }
  const sampleId = stuckChannels.find((c) => c.topic === `${NS}/sample`).id;
  stuck.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 1, channelId: sampleId }] }));
  await sleep(100);
  stuck._socket.pause();

  for (const topic of [`${NS}/sample`, `${NS}/thermal/state`, `${NS}/procedure/state`, `${NS}/procedure/command`]) {
    w.subscribe(topic);
  }
  for (const topic of VIEW_TOPICS) w.subscribe(topic);

  // PAUSE once a sweep runs, then RESUME: the procedure pauses and goes on.
  const states = () => w.got(`${NS}/procedure/state`);
  await waitFor("a sweep to run", () => states().some((s) => s.phase === PHASE_SWEEP), 120_000);
  const cmdDef = w.channels.get(`${NS}/procedure/command`).schema;
  const writer = new MessageWriter(parse(cmdDef, { ros2: true }));
  const cmdChannel = client.advertise({
    topic: `${NS}/procedure/command`,
    encoding: "cdr",
    schemaName: "tyre_msgs/msg/ProcedureCommand",
    schema: cmdDef,
    schemaEncoding: "ros2msg",
  });
  const send = (command) =>
    client.sendMessage(
      cmdChannel,
      writer.writeMessage({
        header: { stamp: { sec: 0, nanosec: 0 }, frame_id: "" },
        command,
        procedure: "",
        operator_name: "node test",
      }),
    );
  send(PAUSE);
  await waitFor("the procedure to pause", () => states().some((s) => s.phase === PHASE_PAUSED), 30_000);
  // Not allowed by this run: refused with a reason, and the procedure does not e-stop.
  send(ESTOP);
  await waitFor("ESTOP to be refused", () => w.statuses.some((s) => /ESTOP is not allowed/.test(s.message)), 10_000);

  // A late joiner is sent the plan and the procedure state at once (as DDS transient-local).
  const late = await connect(url, 5_000);
  const lw = late.w;
  await waitFor("the late joiner's channels", () => lw.channels.size >= 16, 10_000);
  lw.subscribe(`${NS}/foxglove/plan`);
  lw.subscribe(`${NS}/procedure/state`);
  await waitFor(
    "the late joiner's plan and state",
    () => lw.got(`${NS}/foxglove/plan`).length > 0 && lw.got(`${NS}/procedure/state`).length > 0,
    5_000,
  );
  const plan = lw.got(`${NS}/foxglove/plan`).at(-1);
  assert.equal(plan.procedure, states().at(-1).procedure);
  assert.equal(plan.sweep_count, states().at(-1).sweep_count);
  assert.equal(plan.sweeps.length, plan.sweep_count);
  late.client.close();

  send(RESUME);
  const pausedAt = states().findIndex((s) => s.phase === PHASE_PAUSED);
  await waitFor(
    "the procedure to resume",
    () => states().slice(pausedAt).some((s) => s.phase !== PHASE_PAUSED),
    30_000,
  );

  const code = await exited;
  assert.equal(code, 0, `tyrerig run failed:\n${stderr.slice(-3000)}`);
  client.close();
  ws.terminate();
  stuck.terminate();

  // The run as the recorder logged it.
  const logged = await readLog(log, [
    `${NS}/sample`,
    `${NS}/thermal/state`,
    `${NS}/procedure/state`,
    `${NS}/procedure/command`,
  ]);
  assert.ok(states().at(-1).phase === PHASE_COMPLETE, "the live client saw the procedure complete");
  // The suite never waited for the stuck client: every sample reached the recorder, in order.
  const loggedSamples = logged.get(`${NS}/sample`);
  assert.ok(loggedSamples.length > 1000, `${loggedSamples.length} samples logged`);
  loggedSamples.forEach((s, i) => assert.equal(Number(s.seq), i, "sample seq in the log"));

  // Field by field: every RigSample and ThermalState the client decoded is the logged one.
  const bySeq = new Map(loggedSamples.map((s) => [String(s.seq), s]));
  const liveSamples = w.got(`${NS}/sample`);
  assert.ok(liveSamples.length > loggedSamples.length / 2, `client got ${liveSamples.length} samples`);
  for (const s of liveSamples) {
    assert.deepStrictEqual(s, bySeq.get(String(s.seq)), `RigSample seq ${s.seq}`);
  }
  const thermalByStamp = new Map(logged.get(`${NS}/thermal/state`).map((s) => [stampKey(s.header), s]));
  const liveThermal = w.got(`${NS}/thermal/state`);
  assert.ok(liveThermal.length > 100, `client got ${liveThermal.length} thermal states`);
  for (const s of liveThermal) {
    assert.deepStrictEqual(s, thermalByStamp.get(stampKey(s.header)), `ThermalState at ${stampKey(s.header)}`);
  }

  // The commands went through DDS to the sequencer (the recorder logged them), ESTOP did not.
  const commands = logged.get(`${NS}/procedure/command`).map((c) => c.command);
  assert.deepEqual(commands, [PAUSE, RESUME]);
  assert.ok(logged.get(`${NS}/procedure/state`).some((s) => s.phase === PHASE_PAUSED), "the log shows the pause");
  assert.ok(logged.get(`${NS}/procedure/command`).every((c) => c.operator_name === "node test"));

  // The views: progress reached 100 %, the alarms log has the pause, traces carry forces.
  const progress = w.got(`${NS}/foxglove/progress`);
  assert.equal(progress.at(-1).phase, "COMPLETE");
  const alarms = w.got(`${NS}/foxglove/alarms`).map((l) => l.message);
  assert.ok(alarms.some((m) => /-> PAUSED/.test(m)), JSON.stringify(alarms));
  assert.ok(alarms.some((m) => /refused a command/.test(m)), JSON.stringify(alarms));
  const traces = w.got(`${NS}/foxglove/sweep_trace`);
  assert.ok(traces.some((tr) => tr.fx_n.length > 10 && tr.fx_n.length === tr.slip_ratio.length));
});
