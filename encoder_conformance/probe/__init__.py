"""The read-only probe of a live device (``profile from-eds X.eds --probe``): what an EDS cannot say.

It confirms or corrects a profile draft by asking the device: which entries exist and how long they are,
which values change across a reset (not defaults), which TPDO transmission types and abort codes it gives,
which LSS services it answers, block transfer, SYNC producer, heartbeat and node guarding. Everything it
writes it puts back and reads back (``put_back.py``); what it cannot settle stays a numbered ``todo:``.
"""
