"""The servers clients talk to: RTDE (``rtde``, 30004), the dashboard (``dashboard``,
29999), the script port (``script``, 30003), the primary and secondary interfaces
(``primary``, 30001/30002), on a small threaded TCP server (``tcp``)."""
