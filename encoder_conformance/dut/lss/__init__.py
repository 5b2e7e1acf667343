"""LSS: the master (the services' frames), the device's LSS states and steps, finding nodes, the LSS put-back."""
