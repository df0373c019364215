#pragma once
// cpp-httplib for the service and its clients, minus one macro: httplib.h includes <resolv.h>,
// whose `#define _res (*__res_state())` breaks any Eigen header included after it (Eigen names
// a parameter `_res`). Include this instead of <httplib.h>, in any order.
#include <httplib.h>
#undef _res
