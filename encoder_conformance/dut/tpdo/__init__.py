"""TPDOs under test: choosing one, setting it up and putting it back (COB-ID, mapping, while invalid), the
stimuli it is sent on, capturing a periodic stream."""
