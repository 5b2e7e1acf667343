"""The link to the device: the bus connection and its frame log (every test's trace), the device object with
raw frames and its liveness, the windows a wait owes (answer, silence), the time budget the waits are booked in,
the host's clock and lateness."""
