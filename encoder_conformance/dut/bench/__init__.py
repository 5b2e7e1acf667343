"""The bench around the device: power switch and power cycles, the actuator (EMCY stimulus, shaft drive), the encoder
function over SDO (settings, position, reference point) and the shaft mover."""
