//! The FMI 3.0 state machine in every state.
