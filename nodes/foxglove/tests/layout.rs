//! The shipped Foxglove layout (`launch-config/foxglove/tyre-rig.json`) only refers to what the
//! foxglove node serves: every panel in the layout exists, every message path names a served
//! channel and fields its schema has, every indicator rule a value that occurs, and every
//! publish button a command the `.msg` defines.

use foxglove_node::core::phase_name;
use foxglove_node::views::View;
use node_runtime::SuiteTopic;
use serde_json::Value;
use std::collections::BTreeSet;
use tyre_msgs::msgdef::BaseType;

const NS: &str = "/rig";

fn layout() -> Value {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../launch-config/foxglove/tyre-rig.json");
    serde_json::from_str(&std::fs::read_to_string(path).expect("read layout")).expect("layout is JSON")
}

/// Panel ids in a mosaic tree (tabs included).
fn panels_in(node: &Value, config: &Value, out: &mut BTreeSet<String>) {
    match node {
        Value::String(id) => {
            out.insert(id.clone());
            if id.starts_with("Tab!") {
                for tab in config[id]["tabs"].as_array().expect("tabs") {
                    panels_in(&tab["layout"], config, out);
                }
            }
        }
        Value::Object(split) => {
            panels_in(&split["first"], config, out);
            panels_in(&split["second"], config, out);
        }
        other => panic!("not a mosaic node: {other}"),
    }
}

/// Does `fields` (a `.` path below a message of ROS type `ty`) exist?
fn ros_fields_exist(ty: &str, fields: &[&str]) -> Result<(), String> {
    let Some((first, rest)) = fields.split_first() else { return Ok(()) };
    let def = tyre_msgs::schema::find_definition(ty).ok_or(format!("no definition of {ty}"))?;
    let def = def.parse().map_err(|e| e.to_string())?;
    let field = def.field(first).ok_or(format!("{ty} has no field {first}"))?;
    match &field.ty.base {
        BaseType::Message(t) => ros_fields_exist(&t.ros_type_name(), rest),
        _ if rest.is_empty() => Ok(()),
        _ => Err(format!("{ty}.{first} is not a message")),
    }
}

fn json_fields_exist(schema: &Value, fields: &[&str]) -> Result<(), String> {
    let Some((first, rest)) = fields.split_first() else { return Ok(()) };
    let prop = &schema["properties"][first];
    if prop.is_null() {
        return Err(format!("no field {first}"));
    }
    let inner = if prop["type"] == "array" { &prop["items"] } else { prop };
    json_fields_exist(inner, rest)
}

/// Checks a message path such as `/rig/channels/derived{quantity=="x"}.value` or
/// `/rig/foxglove/sweep_trace.fyw_n[:]`.
fn check_path(path: &str) -> Result<(), String> {
    let topics: Vec<(String, Option<SuiteTopic>, Option<View>)> = SuiteTopic::ALL
        .iter()
        .map(|t| (t.full_name(NS), Some(*t), None))
        .chain(View::ALL.iter().map(|v| (v.full_name(NS), None, Some(*v))))
        .collect();
    let (name, suite, view) = topics
        .iter()
        .filter(|(name, _, _)| path.starts_with(name.as_str()))
        .max_by_key(|(name, _, _)| name.len())
        .ok_or(format!("{path}: names no served channel"))?;
    let mut rest = &path[name.len()..];
    let mut filter_field = None;
    if let Some(f) = rest.strip_prefix('{') {
        let end = f.find('}').ok_or(format!("{path}: unclosed filter"))?;
        filter_field = Some(f[..end].split("==").next().unwrap_or("").trim().to_owned());
        rest = &f[end + 1..];
    }
    let rest = rest.strip_prefix('.').unwrap_or(rest);
    let fields: Vec<&str> =
        // A slice (`[:]`) or an index (`[0]`) of an array field names the field itself.
        if rest.is_empty() { Vec::new() } else { rest.split('.').map(|f| f.split('[').next().unwrap_or(f)).collect() };
    let check = |fields: &[&str]| -> Result<(), String> {
        match (suite, view) {
            (Some(t), _) => ros_fields_exist(&t.ros_type_name(), fields),
            (_, Some(v)) => json_fields_exist(&serde_json::from_str(&v.json_schema()).expect("schema"), fields),
            _ => unreachable!(),
        }
    };
    if let Some(f) = filter_field {
        check(&[f.as_str()]).map_err(|e| format!("{path}: filter: {e}"))?;
    }
    check(&fields).map_err(|e| format!("{path}: {e}"))
}

#[test]
fn every_panel_of_the_layout_is_configured_and_used() {
    let l = layout();
    let config = &l["configById"];
    let mut used = BTreeSet::new();
    panels_in(&l["layout"], config, &mut used);
    let configured: BTreeSet<String> = config.as_object().expect("configById").keys().cloned().collect();
    assert_eq!(used, configured);
    // The panels the issue asks for are there.
    for id in ["Plot!fyw_over_slip", "Plot!fx_over_slip", "Plot!tread_temperatures", "Gauge!progress", "Log!alarms"] {
        assert!(configured.contains(id), "{id}");
    }
    for id in ["Plot!wear", "Plot!cornering_stiffness", "Table!plan", "Indicator!phase", "Table!progress"] {
        assert!(configured.contains(id), "{id}");
    }
}

#[test]
fn every_message_path_names_a_served_channel_and_its_fields() {
    let l = layout();
    let mut paths = Vec::new();
    fn collect(v: &Value, key: &str, out: &mut Vec<String>) {
        match v {
            Value::Object(m) => m.iter().for_each(|(k, v)| collect(v, k, out)),
            Value::Array(a) => a.iter().for_each(|v| collect(v, key, out)),
            Value::String(s)
                if matches!(key, "value" | "xValuePath" | "path" | "topicPath" | "topicToRender" | "topicName")
                    && s.starts_with('/') =>
            {
                out.push(s.clone())
            }
            _ => {}
        }
    }
    collect(&l["configById"], "", &mut paths);
    assert!(paths.len() > 25, "{paths:?}");
    let errors: Vec<String> = paths.iter().filter_map(|p| check_path(p).err()).collect();
    assert!(errors.is_empty(), "{errors:#?}");
    // The checker itself refuses what does not exist.
    assert!(check_path("/rig/thermal/state.baseline_degc").is_err());
    assert!(check_path("/rig/foxglove/sweep_trace.fyw_n[:]").is_ok());
    assert!(check_path("/rig/foxglove/sweep_trace.fy_n[:]").is_err());
    assert!(check_path("/rig/foxglove/model.bands[1].lower[:]").is_ok());
    assert!(check_path("/rig/foxglove/model.bands[1].low[:]").is_err());
    assert!(check_path("/rig/channels/derived{quantitty==\"x\"}.value").is_err());
    assert!(check_path("/rig/nothing.value").is_err());
}

#[test]
fn indicators_and_buttons_use_values_that_exist() {
    let l = layout();
    let phases: BTreeSet<&str> = (0..=20).map(phase_name).filter(|n| *n != "?").collect();
    for rule in l["configById"]["Indicator!phase"]["rules"].as_array().expect("rules") {
        let v = rule["rawValue"].as_str().expect("rawValue");
        assert!(phases.contains(v), "phase indicator rule {v:?} is not a phase name ({phases:?})");
    }
    for (id, code) in
        [("Publish!pause", tyre_msgs::ProcedureCommand::PAUSE), ("Publish!resume", tyre_msgs::ProcedureCommand::RESUME)]
    {
        let p = &l["configById"][id];
        assert_eq!(p["datatype"], "tyre_msgs/msg/ProcedureCommand");
        let value: Value = serde_json::from_str(p["value"].as_str().expect("value")).expect("JSON");
        assert_eq!(value["command"], code, "{id}");
        for key in value.as_object().expect("object").keys() {
            ros_fields_exist("tyre_msgs/msg/ProcedureCommand", &[key]).unwrap_or_else(|e| panic!("{id}: {e}"));
        }
    }
}
