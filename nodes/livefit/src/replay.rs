//! A recorded run fed to the live fit: the samples and procedure states of a log in the order
//! the suite produced them (log time; at equal times the sample first, as a headless run writes
//! the state a sample caused after it). For `tyrerig bench live-fit` and the tests.

use mcaplog::LogReader;
use tyre_msgs::{ProcedureState, RigSample, RosMessage};

use crate::core::{LiveFit, Trigger};

/// One input of the live fit.
#[derive(Debug, Clone)]
pub enum Input {
    /// A rig sample.
    Sample(RigSample),
    /// A procedure state.
    State(ProcedureState),
}

fn topic_of<M: RosMessage>(reader: &LogReader) -> Option<String> {
    let want = M::ros_type_name();
    reader.topics().into_iter().find(|t| t.ros_type == want).map(|t| t.topic)
}

/// The live fit's inputs from a log, in order.
pub fn inputs_of_log(reader: &LogReader) -> Result<Vec<Input>, String> {
    let sample_topic = topic_of::<RigSample>(reader).ok_or("the log has no tyre_msgs/msg/RigSample topic")?;
    let state_topic = topic_of::<ProcedureState>(reader).ok_or("the log has no tyre_msgs/msg/ProcedureState topic")?;
    let samples = reader.typed::<RigSample>(&sample_topic).map_err(|e| e.to_string())?;
    let states = reader.typed::<ProcedureState>(&state_topic).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(samples.len() + states.len());
    let mut states = states.into_iter().peekable();
    for (t, s) in samples {
        while let Some((_, st)) = states.next_if(|(ts, _)| *ts < t) {
            out.push(Input::State(st));
        }
        out.push(Input::Sample(s));
    }
    out.extend(states.map(|(_, st)| Input::State(st)));
    Ok(out)
}

/// Feeds one input; returns what it made due.
pub fn feed(core: &mut LiveFit, input: &Input) -> Trigger {
    match input {
        Input::Sample(s) => core.on_sample(s),
        Input::State(st) => core.on_procedure_state(st),
    }
}
