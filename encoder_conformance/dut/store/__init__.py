"""What a device remembers: storing entries its own way (``persist``), counting the commands that wear its memory,
whether it shows what it stored after a restart, what it says at boot about its stored data."""
