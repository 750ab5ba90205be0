// Validates Kubernetes manifests offline (no cluster): every object against the Kubernetes API's JSON
// schema (the `kubernetes-models` package), then the rules this project's deploy files keep:
//   - every container image is built locally (mltfarm-local:...), never :latest, imagePullPolicy IfNotPresent;
//   - every pod runs as non-root with an fsGroup (its volumes are writable by the image's user);
//   - the token comes from a Secret (MLTFARM_TOKEN via secretKeyRef), never a literal;
//   - the coordinator has a memory limit and stops reporting SERVING before it drains (--shutdown-grace).
// A deliberately broken object is checked first: the validator must reject it, or nothing is proven.
// usage: node validate.mjs FILE.yaml...        exit 0 = all valid; 1 = errors (printed)
import { readFileSync } from "node:fs";
import { parseAllDocuments } from "yaml";

async function modelFor(apiVersion, kind) {
  const mod = await import(`kubernetes-models/${apiVersion}/${kind}`).catch(() => null);
  if (!mod || !mod[kind]) throw new Error(`unknown apiVersion/kind ${apiVersion}/${kind}`);
  return mod[kind];
}

async function schemaErrors(obj) {
  try {
    const Model = await modelFor(obj.apiVersion, obj.kind);
    new Model(obj).validate();
    return [];
  } catch (e) {
    return [String(e.message || e)];
  }
}

function podSpecOf(obj) {
  if (obj.kind === "Pod") return obj.spec;
  return obj.spec && obj.spec.template ? obj.spec.template.spec : null;
}

function projectErrors(obj) {
  const errors = [];
  const pod = podSpecOf(obj);
  if (!pod) return errors;
  const sc = pod.securityContext || {};
  if (sc.fsGroup === undefined) errors.push("spec.template.spec.securityContext.fsGroup: not set (volumes must be writable by the image's user)");
  if (sc.runAsNonRoot !== true) errors.push("spec.template.spec.securityContext.runAsNonRoot: must be true");
  for (const c of pod.containers || []) {
    const where = `container ${c.name}`;
    if (!/^mltfarm-local:/.test(c.image || "")) errors.push(`${where}: image '${c.image}' must be the locally built mltfarm-local:TAG`);
    if (/:latest$/.test(c.image || "")) errors.push(`${where}: image '${c.image}' uses :latest`);
    if (c.imagePullPolicy !== "IfNotPresent") errors.push(`${where}: imagePullPolicy must be IfNotPresent (got ${c.imagePullPolicy})`);
    const token = (c.env || []).find((e) => e.name === "MLTFARM_TOKEN");
    if (!token || !token.valueFrom || !token.valueFrom.secretKeyRef) errors.push(`${where}: MLTFARM_TOKEN must come from a Secret (secretKeyRef)`);
    if ((c.args || []).includes("--token")) errors.push(`${where}: --token on the command line`);
    if ((c.command || []).includes("mltfarm-coordinator")) {
      if (!c.resources || !c.resources.limits || !c.resources.limits.memory) errors.push(`${where}: no memory limit`);
      if (!(c.args || []).includes("--shutdown-grace")) errors.push(`${where}: no --shutdown-grace (NOT_SERVING before the drain)`);
    }
  }
  return errors;
}

async function main() {
  const files = process.argv.slice(2);
  if (!files.length) {
    console.error("usage: node validate.mjs FILE.yaml...");
    process.exit(2);
  }
  // The validator itself: a Deployment whose container port is a string and whose replicas is negative.
  const broken = { apiVersion: "apps/v1", kind: "Deployment", metadata: { name: "x" },
    spec: { replicas: "many", selector: { matchLabels: { a: "b" } },
      template: { metadata: { labels: { a: "b" } }, spec: { containers: [{ name: "c", image: "i", ports: [{ containerPort: "http" }] }] } } } };
  await modelFor(broken.apiVersion, broken.kind);  // throws if the package cannot be loaded
  if ((await schemaErrors(broken)).length === 0) {
    console.error("FAIL: the schema validator accepted a broken Deployment: nothing below would be proven");
    process.exit(1);
  }
  let failed = 0, objects = 0;
  for (const file of files) {
    const docs = parseAllDocuments(readFileSync(file, "utf8"));
    for (const doc of docs) {
      if (doc.errors.length) {
        console.error(`${file}: YAML: ${doc.errors.map((e) => e.message).join("; ")}`);
        ++failed;
        continue;
      }
      const obj = doc.toJS();
      if (!obj) continue;
      ++objects;
      const name = `${file}: ${obj.kind || "?"} ${obj.metadata && obj.metadata.name}`;
      const errors = [...(await schemaErrors(obj)), ...projectErrors(obj)];
      if (errors.length) {
        ++failed;
        console.error(`${name}:\n  ${errors.join("\n  ")}`);
      } else {
        console.log(`${name}: valid`);
      }
    }
  }
  console.log(`${objects - failed} passed, ${failed} failed`);
  process.exit(failed || objects === 0 ? 1 : 0);
}

main();
